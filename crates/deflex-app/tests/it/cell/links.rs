//! The link factory, both sides from one `CELL.toml`: every robot protocol binds on loopback on
//! the controller side, and the robot side of every protocol reaches it.

use deflex_app::cell::config::CellFile;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

const KINDS: [&str; 5] = ["kuka-rsi", "abb-egm", "staubli", "simple-udp", "simple-tcp"];

fn cell(kind: &str, robot_port: u16, sensor_port: u16) -> CellFile {
    let text = format!(
        "[robot]\nkind = \"{kind}\"\nbind = \"127.0.0.1:{robot_port}\"\n\
         [sensor]\nkind = \"netft\"\naddress = \"127.0.0.1:{sensor_port}\"\n\
         [model]\nfile = \"tx200\"\n"
    );
    CellFile::parse(&text, "cell.toml", PathBuf::new()).unwrap()
}

#[test]
fn every_robot_kind_binds_on_loopback() {
    for kind in KINDS {
        assert!(cell(kind, 0, 49152).open_robot_link(6).is_ok(), "{kind}");
    }
}

/// For every protocol: the controller side bound on a free port, the robot side opened by the
/// same file towards it; a state sent by the robot side arrives at the controller side with
/// its joints, and the answer arrives back (the simple TCP robot connects first).
#[test]
fn both_sides_of_every_protocol_meet() {
    let q = [0.1, -0.2, 0.3, -0.4, 0.5, -0.6];
    for kind in KINDS {
        let port = if kind == "simple-tcp" {
            std::net::TcpListener::bind("127.0.0.1:0")
                .and_then(|l| l.local_addr())
                .unwrap()
                .port()
        } else {
            std::net::UdpSocket::bind("127.0.0.1:0")
                .and_then(|s| s.local_addr())
                .unwrap()
                .port()
        };
        let file = cell(kind, port, 0);
        let mut controller = file.open_robot_link(6).unwrap();
        let stop = AtomicBool::new(false);
        let mut robot = file
            .robot_side(6)
            .open(Duration::from_secs(5), &stop)
            .unwrap();
        assert_eq!(robot.echoes_cycle(), matches!(kind, "kuka-rsi" | "staubli"));
        let mut state = None;
        for cycle in 1..=50 {
            let sent = deflex_io::RobotState {
                cycle_id: cycle * 4,
                ..deflex_io::RobotState::with_joints(&q)
            };
            robot.send_state(&sent).unwrap();
            if let Ok(Some(s)) = controller.receive(Duration::from_millis(100)) {
                state = Some(s);
                break;
            }
        }
        let state = state.unwrap_or_else(|| panic!("{kind}: no state arrived"));
        for (a, b) in state.joints().iter().zip(q) {
            assert!((a - b).abs() < 1e-4, "{kind}: {:?}", state.joints());
        }
        let correction = deflex_io::Correction::from_array([1e-4, 0.0, -2e-4, 0.0, 0.0, 0.0]);
        controller.send_correction(&correction).unwrap();
        let reply = (0..20)
            .find_map(|_| robot.receive(Duration::from_millis(100)).ok().flatten())
            .unwrap_or_else(|| panic!("{kind}: no answer arrived"));
        let got = reply.correction.to_array();
        assert!(
            (got[0] - 1e-4).abs() < 1e-6 && (got[2] + 2e-4).abs() < 1e-6,
            "{kind}: {got:?}"
        );
    }
}
