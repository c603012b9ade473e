use deflex_io::guard::*;

fn counters(g: &SessionGuard) -> LinkCounters {
    let mut c = LinkCounters::default();
    g.add_to(&mut c);
    c
}

#[test]
fn serial_arithmetic() {
    assert!(advances(1, 0));
    assert!(advances(5, 1));
    assert!(!advances(1, 1), "a duplicate");
    assert!(!advances(0, 1), "a replay");
    // Wrap of a 32-bit counter.
    assert!(advances(0, u64::from(u32::MAX)));
    assert!(advances(3, u64::from(u32::MAX) - 2));
    assert!(!advances(u64::from(u32::MAX), 0));
    // Half the space ahead is ahead, beyond that is behind.
    assert!(advances((1 << 31) - 1, 0));
    assert!(!advances(1 << 31, 0));
    // Wider values: plain order.
    assert!(advances(1 << 40, 1 << 33));
    assert!(!advances(1 << 33, 1 << 40));
    assert!(advances(1 << 33, 5));
    assert!(!advances(5, 1 << 33));
}

#[test]
fn stamps() {
    use Stamp::*;
    assert!(Millis32(3).before(Millis32(4)));
    assert!(!Millis32(4).before(Millis32(4)), "equal is not back");
    assert!(!Millis32(1).before(Millis32(u32::MAX)), "wrapped forward");
    assert!(Millis32(0).before(Millis32(1000)));
    assert!(Seconds(0.5).before(Seconds(0.6)));
    assert!(!Seconds(0.6).before(Seconds(0.6)));
    assert!(!Seconds(1.0).before(Millis32(5)));
    assert_eq!(Millis32(1500).seconds(), 1.5);
}

#[test]
fn each_rule_drops_and_counts_without_changing_the_session() {
    let mut g = SessionGuard::new();
    let t = |ms| Some(Stamp::Millis32(ms));
    assert_eq!(g.admit(6, Some(10), t(100)), Ok(()));
    assert_eq!(g.joint_count(), Some(6));
    assert_eq!(
        g.admit(5, Some(11), t(104)),
        Err(DropReason::JointCount { got: 5, session: 6 })
    );
    assert_eq!(
        g.admit(6, Some(10), t(104)),
        Err(DropReason::SequenceNotAdvancing { got: 10, last: 10 })
    );
    assert_eq!(
        g.admit(6, Some(9), t(104)),
        Err(DropReason::SequenceNotAdvancing { got: 9, last: 10 })
    );
    assert_eq!(
        g.admit(6, Some(11), t(0)),
        Err(DropReason::TimeWentBack {
            got_s: 0.0,
            last_s: 0.1
        })
    );
    assert!(matches!(
        g.admit(6, None, t(104)),
        Err(DropReason::SequenceMismatch {
            message_has_one: false
        })
    ));
    // None of the drops moved the session: 11 at 100 ms (equal time) is next.
    assert_eq!(g.admit(6, Some(11), t(100)), Ok(()));
    assert_eq!(g.admit(6, Some(13), t(108)), Ok(()), "a gap is fine");
    let c = counters(&g);
    assert_eq!(
        (
            c.accepted,
            c.dropped_joint_count,
            c.dropped_sequence,
            c.dropped_time,
            c.dropped_sequence_mismatch,
            c.dropped()
        ),
        (3, 1, 2, 1, 1, 5)
    );
    // A new stream forgets the numbers, not the joint count.
    g.restart_stream();
    assert_eq!(g.admit(6, Some(1), t(0)), Ok(()));
    assert!(g.admit(7, Some(2), t(4)).is_err());
}

#[test]
fn sessions_without_sequence_numbers() {
    let mut g = SessionGuard::new();
    for _ in 0..3 {
        assert_eq!(g.admit(4, None, None), Ok(()));
    }
    assert_eq!(
        g.admit(4, Some(1), None),
        Err(DropReason::SequenceMismatch {
            message_has_one: true
        })
    );
    assert!(g.admit(6, None, None).is_err());
    let msg = DropReason::SequenceNotAdvancing { got: 3, last: 4 }.to_string();
    assert!(
        msg.contains('3') && msg.contains('4') && msg.contains("replay"),
        "{msg}"
    );
}
