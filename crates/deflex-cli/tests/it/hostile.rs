//! The hostile sweep (issue 18): every command given special, huge, truncated, binary and
//! nonsensical files as inputs, and devices, FIFOs, sockets, links, foreign folders and its own
//! inputs as outputs. Each case must end (no hang: a generous per-case limit, not a timing
//! claim), exit non-zero without a panic, name the file or flag in its message, print no raw
//! control character, and leave every file of the fixture as it was (nothing replaced, nothing
//! left behind), `/dev/null` a character device.
//!
//! `cargo test` runs a fixed subset (every output case, one bad file per input slot in turn,
//! the numeric cases); the whole sweep (over 1,000 cases) runs with
//! `scripts/hostile-sweep` (`cargo test -p deflex-cli --test it hostile_sweep_full --
//! --ignored --nocapture`), which prints its counts.

use std::collections::BTreeMap;
use std::os::unix::fs::{FileTypeExt, MetadataExt};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// A case that has not ended after this long is a hang (the slowest case takes well under a
/// second on a loaded 2-core machine; this bounds a failure, it measures nothing).
const HANG_LIMIT: Duration = Duration::from_secs(120);

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_deflex")
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// What a good file in a slot is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Slot {
    Robot,
    Measurements,
    Plan,
    Absolute,
    Cell,
    Twin,
    Gcode,
    Log,
    ProgramConfig,
}

/// The fixture: good files of every kind, in a scratch folder.
struct Fixture {
    dir: PathBuf,
    good: BTreeMap<&'static str, PathBuf>,
}

fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(path.as_os_str().as_encoded_bytes()).unwrap();
    // SAFETY: mkfifo with a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "{path:?}");
}

fn run_ok(args: &[&str]) {
    let out = Command::new(bin()).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "fixture: deflex {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

impl Fixture {
    fn new(tag: &str) -> Fixture {
        let dir = std::env::temp_dir().join(format!("deflex-hostile-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("good")).unwrap();
        std::fs::create_dir_all(dir.join("bad")).unwrap();
        let g = |name: &str| dir.join("good").join(name);
        let mut good = BTreeMap::new();
        let robot = g("tx200.toml");
        std::fs::copy(repo().join("crates/deflex-model/robots/tx200.toml"), &robot).unwrap();
        good.insert("robot", robot);
        let plan = g("plan.csv");
        run_ok(&["plan", "--robot", "tx200", "--out", plan.to_str().unwrap()]);
        good.insert("plan", plan.clone());
        let meas = g("meas.csv");
        run_ok(&[
            "sim",
            "campaign",
            "--robot",
            "tx200",
            "--plan",
            plan.to_str().unwrap(),
            "--out",
            meas.to_str().unwrap(),
        ]);
        good.insert("meas", meas);
        let gcode = g("part.nc");
        std::fs::write(
            &gcode,
            "G21 G90\nG0 X0 Y0 Z5\nG1 Z0 F600\nG1 X20\nG1 Y20\nG1 X0\nG1 Y0\nG0 Z5\n",
        )
        .unwrap();
        good.insert("gcode", gcode);
        let cell = g("cell.toml");
        std::fs::write(
            &cell,
            "[robot]\nkind = \"kuka-rsi\"\nbind = \"127.0.0.1:1\"\ntimeout_s = 0.2\n\
             [sensor]\nkind = \"netft\"\naddress = \"127.0.0.1:2\"\nbind = \"127.0.0.1:0\"\n\
             timeout_s = 0.2\n[model]\nfile = \"tx200\"\n[control]\nrealtime = false\n\
             lock_memory = false\n",
        )
        .unwrap();
        good.insert("cell", cell);
        let twin = g("twin.toml");
        std::fs::write(&twin, "[cell.controller]\nrate_hz = 100.0\n").unwrap();
        good.insert("twin", twin);
        let log = g("log.csv");
        std::fs::write(&log, "time_s,des_x_mm\n0,0\n0.01,0.1\n").unwrap();
        good.insert("log", log);
        let program = g("program.toml");
        std::fs::copy(repo().join("docs/program.example.toml"), &program).unwrap();
        good.insert("program", program);
        let keep = dir.join("keep.txt");
        std::fs::write(&keep, "precious").unwrap();
        Fixture { dir, good }
    }

    fn good(&self, slot: Slot) -> PathBuf {
        let key = match slot {
            Slot::Robot => "robot",
            Slot::Measurements => "meas",
            Slot::Plan | Slot::Absolute => "plan",
            Slot::Cell => "cell",
            Slot::Twin => "twin",
            Slot::Gcode => "gcode",
            Slot::Log => "log",
            Slot::ProgramConfig => "program",
        };
        self.good[key].clone()
    }

    /// Every entry under the fixture folder with what identifies its content (type, size,
    /// inode, modification time): "nothing replaced, nothing left behind". The locks of folder
    /// outputs (`.NAME.lock`, kept on purpose) are left out.
    fn snapshot(&self) -> BTreeMap<PathBuf, (u32, u64, u64, i64, i64)> {
        let mut out = BTreeMap::new();
        let mut stack = vec![self.dir.clone()];
        while let Some(d) = stack.pop() {
            let Ok(entries) = std::fs::read_dir(&d) else {
                continue;
            };
            for e in entries.flatten() {
                let p = e.path();
                let name = e.file_name().to_string_lossy().into_owned();
                if name.starts_with('.') && name.ends_with(".lock") {
                    continue;
                }
                let Ok(m) = std::fs::symlink_metadata(&p) else {
                    continue;
                };
                out.insert(
                    p.clone(),
                    (m.mode(), m.len(), m.ino(), m.mtime(), m.mtime_nsec()),
                );
                if m.is_dir() {
                    stack.push(p);
                }
            }
        }
        out
    }
}

impl Drop for Fixture {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// One bad input: how it is made from the slot's good file.
#[derive(Clone, Copy, Debug)]
enum BadInput {
    DevZero,
    DevUrandom,
    DevNull,
    Fifo,
    Folder,
    LinkToDevZero,
    LinkToFifo,
    Dangling,
    LinkLoop,
    Missing,
    Empty,
    Huge,
    Binary,
    Truncated,
    NotANumber,
    Enormous,
    ControlCharacters,
    LongLine,
    NotUtf8,
    EscapeInName,
    ProcFile,
    Socket,
    DevFull,
    StdinAlias,
}

const BAD_INPUTS: [BadInput; 24] = [
    BadInput::DevZero,
    BadInput::DevUrandom,
    BadInput::DevNull,
    BadInput::Fifo,
    BadInput::Folder,
    BadInput::LinkToDevZero,
    BadInput::LinkToFifo,
    BadInput::Dangling,
    BadInput::LinkLoop,
    BadInput::Missing,
    BadInput::Empty,
    BadInput::Huge,
    BadInput::Binary,
    BadInput::Truncated,
    BadInput::NotANumber,
    BadInput::Enormous,
    BadInput::ControlCharacters,
    BadInput::LongLine,
    BadInput::NotUtf8,
    BadInput::EscapeInName,
    BadInput::ProcFile,
    BadInput::Socket,
    BadInput::DevFull,
    BadInput::StdinAlias,
];

/// Replace every number of `text` (outside comments) by `with`.
fn replace_numbers(text: &str, with: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.lines() {
        if line.trim_start().starts_with('#') || line.trim_start().starts_with('[') {
            out.push_str(line);
        } else {
            let mut in_number = false;
            for c in line.chars() {
                let digit = c.is_ascii_digit() || (in_number && (c == '.' || c == 'e'));
                if digit {
                    if !in_number {
                        out.push_str(with);
                    }
                    in_number = true;
                } else {
                    in_number = false;
                    out.push(c);
                }
            }
        }
        out.push('\n');
    }
    out
}

/// Make the bad input `bad` for a slot whose good file is `good`; `n` makes names unique.
fn make_bad(fx: &Fixture, bad: BadInput, good: &Path, n: usize) -> PathBuf {
    let b = fx.dir.join("bad");
    let ext = good
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let path = b.join(format!("case{n}{ext}"));
    let text = std::fs::read_to_string(good).unwrap_or_default();
    match bad {
        BadInput::DevZero => return PathBuf::from("/dev/zero"),
        BadInput::DevUrandom => return PathBuf::from("/dev/urandom"),
        BadInput::DevNull => return PathBuf::from("/dev/null"),
        BadInput::Fifo => mkfifo(&path),
        BadInput::Folder => std::fs::create_dir(&path).unwrap(),
        BadInput::LinkToDevZero => std::os::unix::fs::symlink("/dev/zero", &path).unwrap(),
        BadInput::LinkToFifo => {
            let fifo = b.join(format!("fifo{n}"));
            mkfifo(&fifo);
            std::os::unix::fs::symlink(&fifo, &path).unwrap();
        }
        BadInput::Dangling => {
            std::os::unix::fs::symlink(b.join(format!("nothing{n}")), &path).unwrap()
        }
        BadInput::LinkLoop => {
            let other = b.join(format!("loop{n}"));
            std::os::unix::fs::symlink(&other, &path).unwrap();
            std::os::unix::fs::symlink(&path, &other).unwrap();
        }
        BadInput::Missing => {}
        BadInput::Empty => std::fs::write(&path, "").unwrap(),
        BadInput::Huge => {
            // Sparse: 3 GB on paper, nothing on disk; the reader must stop at its limit.
            let f = std::fs::File::create(&path).unwrap();
            f.set_len(3 << 30).unwrap();
        }
        BadInput::Binary => {
            let mut x: u64 = 0x9E37_79B9_7F4A_7C15 ^ n as u64;
            let bytes: Vec<u8> = (0..65536)
                .map(|_| {
                    x ^= x << 13;
                    x ^= x >> 7;
                    x ^= x << 17;
                    (x >> 24) as u8
                })
                .collect();
            std::fs::write(&path, bytes).unwrap();
        }
        BadInput::Truncated => {
            let cut = text.len() * 3 / 5;
            let cut = (0..=cut)
                .rev()
                .find(|i| text.is_char_boundary(*i))
                .unwrap_or(0);
            // Cut inside a line, and make sure something is missing.
            std::fs::write(&path, format!("{}\u{0}", &text[..cut])).unwrap();
        }
        BadInput::NotANumber => std::fs::write(&path, replace_numbers(&text, "nan")).unwrap(),
        BadInput::Enormous => std::fs::write(&path, replace_numbers(&text, "1e300")).unwrap(),
        BadInput::ControlCharacters => std::fs::write(
            &path,
            replace_numbers(&text, "\u{1b}[2J\u{1b}]0;owned\u{7}\r"),
        )
        .unwrap(),
        BadInput::LongLine => std::fs::write(&path, "x".repeat(4 << 20)).unwrap(),
        BadInput::NotUtf8 => {
            let mut bytes = text.into_bytes();
            let at = bytes.len() / 2;
            bytes.splice(at..at, [0xff, 0xfe, 0xc0]);
            std::fs::write(&path, bytes).unwrap();
        }
        BadInput::EscapeInName => {
            let named = b.join(format!("case{n}\u{1b}[31mred\r{ext}"));
            std::fs::write(&named, replace_numbers(&text, "nan")).unwrap();
            return named;
        }
        BadInput::ProcFile => return PathBuf::from("/proc/self/mem"),
        BadInput::DevFull => return PathBuf::from("/dev/full"),
        // The process's standard input (here /dev/null), by its /proc alias.
        BadInput::StdinAlias => return PathBuf::from("/proc/self/fd/0"),
        BadInput::Socket => {
            let listener = std::os::unix::net::UnixListener::bind(&path).unwrap();
            std::mem::forget(listener);
        }
    }
    path
}

/// A command template: its arguments, `{IN}` the slot under test, `{OUT}` a fresh output
/// path, `{G:slot}` a good file.
struct Template {
    name: &'static str,
    slot: Slot,
    args: &'static [&'static str],
}

const INPUT_TEMPLATES: &[Template] = &[
    Template {
        name: "model show --robot",
        slot: Slot::Robot,
        args: &["model", "show", "--robot", "{IN}"],
    },
    Template {
        name: "pose --robot",
        slot: Slot::Robot,
        args: &["pose", "--robot", "{IN}", "--q-deg", "0,-90,90,0,0,0"],
    },
    Template {
        name: "deflect --robot",
        slot: Slot::Robot,
        args: &[
            "deflect",
            "--robot",
            "{IN}",
            "--q-deg",
            "0,-90,90,0,0,0",
            "--wrench",
            "0,0,-1000,0,0,0",
        ],
    },
    Template {
        name: "ik --robot",
        slot: Slot::Robot,
        args: &[
            "ik",
            "--robot",
            "{IN}",
            "--xyz-mm",
            "1500,0,500",
            "--rpy-deg",
            "180,0,0",
        ],
    },
    Template {
        name: "map --robot",
        slot: Slot::Robot,
        args: &["map", "--robot", "{IN}", "--out", "{OUT}"],
    },
    Template {
        name: "calibrate --robot",
        slot: Slot::Robot,
        args: &[
            "calibrate",
            "--robot",
            "{IN}",
            "--data",
            "{G:meas}",
            "--out",
            "{OUT}",
        ],
    },
    Template {
        name: "calibrate --data",
        slot: Slot::Measurements,
        args: &[
            "calibrate",
            "--robot",
            "tx200",
            "--data",
            "{IN}",
            "--out",
            "{OUT}",
        ],
    },
    Template {
        name: "validate --robot",
        slot: Slot::Robot,
        args: &["validate", "--robot", "{IN}", "--data", "{G:meas}"],
    },
    Template {
        name: "validate --data",
        slot: Slot::Measurements,
        args: &["validate", "--robot", "tx200", "--data", "{IN}"],
    },
    Template {
        name: "plan --robot",
        slot: Slot::Robot,
        args: &["plan", "--robot", "{IN}", "--out", "{OUT}"],
    },
    Template {
        name: "calibrate-geometry --data",
        slot: Slot::Absolute,
        args: &[
            "calibrate-geometry",
            "--robot",
            "ur10",
            "--data",
            "{IN}",
            "--out",
            "{OUT}",
        ],
    },
    Template {
        name: "calibrate-geometry --robot",
        slot: Slot::Robot,
        args: &[
            "calibrate-geometry",
            "--robot",
            "{IN}",
            "--data",
            "{G:plan}",
            "--out",
            "{OUT}",
        ],
    },
    Template {
        name: "predict --data",
        slot: Slot::Absolute,
        args: &[
            "predict", "--robot", "ur10", "--data", "{IN}", "--out", "{OUT}",
        ],
    },
    Template {
        name: "register --data",
        slot: Slot::Absolute,
        args: &[
            "register", "--robot", "ur10", "--data", "{IN}", "--out", "{OUT}",
        ],
    },
    Template {
        name: "import ur10-tracker --series",
        slot: Slot::Absolute,
        args: &[
            "import",
            "ur10-tracker",
            "--series",
            "{IN}",
            "--setup",
            "S1",
            "--target",
            "T1",
            "--out",
            "{OUT}",
        ],
    },
    Template {
        name: "export --robot",
        slot: Slot::Robot,
        args: &[
            "export", "--robot", "{IN}", "--format", "urdf", "--out", "{OUT}",
        ],
    },
    Template {
        name: "compensate --path",
        slot: Slot::Gcode,
        args: &[
            "compensate",
            "--robot",
            "tx200",
            "--path",
            "{IN}",
            "--out",
            "{OUT}",
        ],
    },
    Template {
        name: "compensate --robot",
        slot: Slot::Robot,
        args: &[
            "compensate",
            "--robot",
            "{IN}",
            "--path",
            "{G:gcode}",
            "--out",
            "{OUT}",
        ],
    },
    Template {
        name: "compensate --program-config",
        slot: Slot::ProgramConfig,
        args: &[
            "compensate",
            "--robot",
            "tx200",
            "--path",
            "{G:gcode}",
            "--program-config",
            "{IN}",
            "--out",
            "{OUT}",
        ],
    },
    Template {
        name: "model fk --joints",
        slot: Slot::Log,
        args: &[
            "model", "fk", "--robot", "tx200", "--joints", "{IN}", "--out", "{OUT}",
        ],
    },
    Template {
        name: "compensate --wrench log:",
        slot: Slot::Log,
        args: &[
            "compensate",
            "--robot",
            "tx200",
            "--path",
            "{G:gcode}",
            "--wrench",
            "log:{IN}",
            "--out",
            "{OUT}",
        ],
    },
    Template {
        name: "compensate --twin",
        slot: Slot::Twin,
        args: &[
            "compensate",
            "--robot",
            "tx200",
            "--path",
            "{G:gcode}",
            "--twin",
            "{IN}",
            "--out",
            "{OUT}",
        ],
    },
    Template {
        name: "sim campaign --plan",
        slot: Slot::Plan,
        args: &[
            "sim", "campaign", "--robot", "tx200", "--plan", "{IN}", "--out", "{OUT}",
        ],
    },
    Template {
        name: "sim campaign --config",
        slot: Slot::Twin,
        args: &[
            "sim", "campaign", "--config", "{IN}", "--plan", "{G:plan}", "--out", "{OUT}",
        ],
    },
    Template {
        name: "sim robot --robot",
        slot: Slot::Robot,
        args: &["sim", "robot", "--robot", "{IN}", "--out", "{OUT}"],
    },
    Template {
        name: "sim isf --config",
        slot: Slot::Twin,
        args: &["sim", "isf", "--config", "{IN}", "--out", "{OUT}"],
    },
    Template {
        name: "run --config",
        slot: Slot::Cell,
        args: &[
            "run",
            "--config",
            "{IN}",
            "--quiet",
            "--startup-timeout-s",
            "0.5",
        ],
    },
    Template {
        name: "cell --config",
        slot: Slot::Cell,
        args: &["cell", "--sim", "--config", "{IN}", "--wait-s", "0.5"],
    },
    Template {
        name: "plot LOG",
        slot: Slot::Log,
        args: &["plot", "{IN}", "--out", "{OUT}"],
    },
];

/// Commands and the outputs they write (`{OUT}` the output under test), with the flag.
const OUTPUT_TEMPLATES: &[(&str, bool, &[&str])] = &[
    (
        "--out",
        false,
        &["plan", "--robot", "tx200", "--out", "{OUT}"],
    ),
    (
        "--out",
        false,
        &[
            "calibrate",
            "--robot",
            "tx200",
            "--data",
            "{G:meas}",
            "--out",
            "{OUT}",
        ],
    ),
    (
        "--report",
        true,
        &[
            "calibrate",
            "--robot",
            "tx200",
            "--data",
            "{G:meas}",
            "--out",
            "{FRESH}",
            "--report",
            "{OUT}",
        ],
    ),
    (
        "--out",
        false,
        &[
            "calibrate-geometry",
            "--robot",
            "ur10",
            "--data",
            "{G:plan}",
            "--out",
            "{OUT}",
        ],
    ),
    (
        "--report",
        true,
        &[
            "calibrate-geometry",
            "--robot",
            "ur10",
            "--data",
            "{G:plan}",
            "--out",
            "{FRESH}",
            "--report",
            "{OUT}",
        ],
    ),
    (
        "--out",
        false,
        &[
            "predict", "--robot", "ur10", "--data", "{G:plan}", "--out", "{OUT}",
        ],
    ),
    (
        "--out",
        false,
        &[
            "register", "--robot", "ur10", "--data", "{G:plan}", "--out", "{OUT}",
        ],
    ),
    (
        "--out",
        false,
        &[
            "import",
            "ur10-tracker",
            "--series",
            "{G:plan}",
            "--setup",
            "S",
            "--target",
            "T",
            "--out",
            "{OUT}",
        ],
    ),
    (
        "--out",
        true,
        &[
            "validate", "--robot", "tx200", "--data", "{G:meas}", "--out", "{OUT}",
        ],
    ),
    (
        "--out",
        false,
        &[
            "sim", "campaign", "--robot", "tx200", "--plan", "{G:plan}", "--out", "{OUT}",
        ],
    ),
    (
        "--out",
        false,
        &["sim", "robot", "--robot", "tx200", "--out", "{OUT}"],
    ),
    ("--out", true, &["sim", "isf", "--out", "{OUT}"]),
    ("--out", true, &["sim", "sensitivity", "--out", "{OUT}"]),
    (
        "--out",
        true,
        &[
            "compensate",
            "--robot",
            "tx200",
            "--path",
            "{G:gcode}",
            "--out",
            "{OUT}",
        ],
    ),
    (
        "--out",
        false,
        &[
            "export", "--robot", "tx200", "--format", "urdf", "--out", "{OUT}",
        ],
    ),
    (
        "--out",
        true,
        &["map", "--robot", "tx200", "--out", "{OUT}"],
    ),
    ("--out", true, &["demo", "--out", "{OUT}"]),
    ("--out", true, &["plot", "{G:log}", "--out", "{OUT}"]),
];

/// A bad output, made in the fixture's `bad` folder.
#[derive(Clone, Copy, Debug)]
enum BadOutput {
    LinkToDevNull,
    Fifo,
    LinkToFifo,
    Socket,
    Dangling,
    FolderForAFile,
    FileForAFolder,
    ForeignFolder,
    UnderAFile,
    AnInput,
    HoldsAnInput,
}

const BAD_OUTPUTS: [BadOutput; 11] = [
    BadOutput::LinkToDevNull,
    BadOutput::Fifo,
    BadOutput::LinkToFifo,
    BadOutput::Socket,
    BadOutput::Dangling,
    BadOutput::FolderForAFile,
    BadOutput::FileForAFolder,
    BadOutput::ForeignFolder,
    BadOutput::UnderAFile,
    BadOutput::AnInput,
    BadOutput::HoldsAnInput,
];

/// The bad output `bad` (`folder`: the command writes a folder); `None` when it does not apply.
fn make_bad_output(
    fx: &Fixture,
    bad: BadOutput,
    folder: bool,
    args: &[&str],
    n: usize,
) -> Option<PathBuf> {
    let b = fx.dir.join("bad");
    let path = b.join(format!("out{n}"));
    match bad {
        BadOutput::LinkToDevNull => std::os::unix::fs::symlink("/dev/null", &path).unwrap(),
        BadOutput::Fifo => mkfifo(&path),
        BadOutput::LinkToFifo => {
            let fifo = b.join(format!("outfifo{n}"));
            mkfifo(&fifo);
            std::os::unix::fs::symlink(&fifo, &path).unwrap();
        }
        BadOutput::Socket => {
            std::mem::forget(std::os::unix::net::UnixListener::bind(&path).unwrap());
        }
        BadOutput::Dangling => {
            std::os::unix::fs::symlink(b.join(format!("gone{n}/x")), &path).unwrap()
        }
        BadOutput::FolderForAFile if !folder => std::fs::create_dir(&path).unwrap(),
        BadOutput::FileForAFolder if folder => std::fs::write(&path, "a file").unwrap(),
        BadOutput::ForeignFolder if folder => {
            std::fs::create_dir(&path).unwrap();
            std::fs::write(path.join("thesis.tex"), "years of work").unwrap();
        }
        BadOutput::UnderAFile => return Some(fx.dir.join("keep.txt").join("out")),
        BadOutput::AnInput if !folder => {
            // The command's own data file (or robot file) as its output.
            let input = args
                .iter()
                .find_map(|a| a.strip_prefix("{G:"))
                .map(|k| fx.good[k.trim_end_matches('}')].clone())?;
            return Some(input);
        }
        BadOutput::HoldsAnInput if folder && args.iter().any(|a| a.starts_with("{G:")) => {
            return Some(fx.dir.join("good"));
        }
        _ => return None,
    }
    Some(path)
}

/// One case's verdict.
#[derive(Debug, Default)]
struct Tally {
    cases: usize,
    hangs: Vec<String>,
    panics: Vec<String>,
    accepted: Vec<String>,
    unnamed: Vec<String>,
    raw_control: Vec<String>,
    changed: Vec<String>,
}

impl Tally {
    fn failures(&self) -> usize {
        self.hangs.len()
            + self.panics.len()
            + self.accepted.len()
            + self.unnamed.len()
            + self.raw_control.len()
            + self.changed.len()
    }

    fn report(&self) -> String {
        let mut s = format!(
            "{} cases: {} hangs, {} panics, {} silent accepts, {} without the file or flag named, {} with raw control characters, {} with files changed",
            self.cases,
            self.hangs.len(),
            self.panics.len(),
            self.accepted.len(),
            self.unnamed.len(),
            self.raw_control.len(),
            self.changed.len()
        );
        for (what, list) in [
            ("hang", &self.hangs),
            ("panic", &self.panics),
            ("accepted", &self.accepted),
            ("unnamed", &self.unnamed),
            ("raw control", &self.raw_control),
            ("changed", &self.changed),
        ] {
            for case in list.iter().take(40) {
                s.push_str(&format!("\n  {what}: {case}"));
            }
        }
        s
    }
}

/// Run `args`; `needles`: one of them must be in the message.
fn run_case(fx: &Fixture, tally: &mut Tally, label: &str, args: &[String], needles: &[String]) {
    tally.cases += 1;
    let before = fx.snapshot();
    let logs = fx
        .dir
        .join("..")
        .join(format!("deflex-hostile-logs-{}", std::process::id()));
    std::fs::create_dir_all(&logs).unwrap();
    let (out_path, err_path) = (logs.join("stdout"), logs.join("stderr"));
    let mut child = Command::new(bin())
        .args(args)
        .current_dir(&logs)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out_path).unwrap())
        .stderr(std::fs::File::create(&err_path).unwrap())
        .spawn()
        .unwrap();
    let started = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break Some(status);
        }
        if started.elapsed() > HANG_LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let stderr =
        String::from_utf8_lossy(&std::fs::read(&err_path).unwrap_or_default()).into_owned();
    let case = format!("{label}: deflex {}", shown_args(args));
    match status {
        None => tally.hangs.push(case.clone()),
        Some(s) if s.success() => tally.accepted.push(case.clone()),
        Some(s) if s.code() == Some(101) || s.code().is_none() || stderr.contains("panicked") => {
            tally
                .panics
                .push(format!("{case}: {}", first_line(&stderr)))
        }
        Some(_) => {
            if !needles.iter().any(|n| stderr.contains(n.as_str())) {
                tally
                    .unnamed
                    .push(format!("{case}: {}", first_line(&stderr)));
            }
            if stderr.chars().any(|c| c.is_control() && c != '\n') {
                tally.raw_control.push(case.clone());
            }
        }
    }
    let after = fx.snapshot();
    let dev_null_ok = std::fs::metadata("/dev/null").is_ok_and(|m| m.file_type().is_char_device());
    if before != after || !dev_null_ok {
        let mut diff: Vec<String> = after
            .iter()
            .filter(|(k, v)| before.get(*k) != Some(v))
            .map(|(k, _)| format!("+{}", k.display()))
            .collect();
        diff.extend(
            before
                .keys()
                .filter(|k| !after.contains_key(*k))
                .map(|k| format!("-{}", k.display())),
        );
        tally
            .changed
            .push(format!("{case}: {diff:?} /dev/null ok: {dev_null_ok}"));
    }
}

fn shown_args(args: &[String]) -> String {
    args.iter()
        .map(|a| a.escape_debug().to_string())
        .collect::<Vec<_>>()
        .join(" ")
}

fn first_line(text: &str) -> String {
    text.lines()
        .find(|l| l.starts_with("error"))
        .unwrap_or(text.lines().next().unwrap_or(""))
        .chars()
        .take(300)
        .collect::<String>()
        .escape_debug()
        .to_string()
}

/// `{IN}`, `{OUT}`, `{FRESH}` and `{G:…}` filled in.
fn fill(fx: &Fixture, args: &[&str], input: &Path, out: &Path, n: usize) -> Vec<String> {
    args.iter()
        .map(|a| {
            let fresh = fx.dir.join("bad").join(format!("fresh{n}"));
            let mut s = a.replace("{IN}", input.to_str().unwrap_or(""));
            s = s.replace("{OUT}", out.to_str().unwrap());
            s = s.replace("{FRESH}", fresh.to_str().unwrap());
            for (k, v) in &fx.good {
                s = s.replace(&format!("{{G:{k}}}"), v.to_str().unwrap());
            }
            s
        })
        .collect()
}

/// Names by which a message may name `path`: the path as shown (control characters escaped)
/// or its file name.
fn names_of(path: &Path) -> Vec<String> {
    let mut names = vec![path.display().to_string().escape_default().to_string()];
    let shown = deflex_shown(&path.display().to_string());
    names.push(shown);
    if let Some(name) = path.file_name() {
        names.push(deflex_shown(&name.to_string_lossy()));
    }
    names
}

/// As `deflex_files::shown` escapes (control characters as `\n`, `\r`, `\t`, `\u{..}`).
fn deflex_shown(text: &str) -> String {
    let mut out = String::new();
    for c in text.chars() {
        match c {
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => out.push_str(&format!("\\u{{{:x}}}", c as u32)),
            c => out.push(c),
        }
    }
    out
}

/// Content variants of robot files, cell files and measurement files (what a careless or
/// hostile user writes), by slot.
fn content_variants(slot: Slot, good: &str) -> Vec<(&'static str, String)> {
    let mut v: Vec<(&'static str, String)> = Vec::new();
    match slot {
        Slot::Robot => {
            v.push(("garbage TOML", "[[joint\nname = ".into()));
            v.push(("no joints", "name = \"x\"\n".into()));
            v.push((
                "three limits",
                good.replacen("limits = [", "limits = [0.0, ", 1),
            ));
            v.push(("stiffness zero", good.replace("z = 2.32e6", "z = 0.0")));
            v.push((
                "stiffness negative",
                good.replace("z = 2.32e6", "z = -2.32e6"),
            ));
            v.push(("a missing", drop_key(good, "a")));
            v.push(("d missing", drop_key(good, "d")));
            v.push(("alpha missing", drop_key(good, "alpha")));
            v.push(("theta_offset missing", drop_key(good, "theta_offset")));
            v.push(("urdf fifo", format!("urdf = \"/dev/zero\"\n{good}")));
            v.push(("nan", replace_numbers(good, "nan")));
            v.push(("inf", replace_numbers(good, "inf")));
            v.push(("1e308", replace_numbers(good, "1e308")));
            v.push(("10000 joints", {
                let joint = good.split("[[joint]]").nth(1).unwrap_or("").to_string();
                let head = good.split("[[joint]]").next().unwrap_or("").to_string();
                head + &format!("[[joint]]{joint}").repeat(10_000)
            }));
        }
        Slot::Measurements | Slot::Plan | Slot::Absolute => {
            let header = good.lines().find(|l| !l.starts_with('#')).unwrap_or("");
            let first = good
                .lines()
                .filter(|l| !l.starts_with('#'))
                .nth(1)
                .unwrap_or("")
                .to_string();
            v.push(("header only", format!("{header}\n")));
            v.push(("one row", format!("{header}\n{first}\n")));
            v.push((
                "500 identical rows",
                format!("{header}\n{}", format!("{first}\n").repeat(500)),
            ));
            v.push(("sigma typo", {
                // A `sigma_mm` column (for `sigma_m`): once ignored, its values replaced by
                // the default σ.
                let mut header_seen = false;
                good.lines()
                    .map(|l| {
                        if l.starts_with('#') || l.is_empty() {
                            l.to_string()
                        } else if !header_seen {
                            header_seen = true;
                            format!("{l},sigma_mm")
                        } else {
                            format!("{l},0.01")
                        }
                    })
                    .collect::<Vec<_>>()
                    .join("\n")
            }));
            v.push(("duplicated column", {
                let cols: Vec<&str> = header.split(',').collect();
                let dup = format!("{header},{}", cols.first().unwrap_or(&""));
                good.replacen(header, &dup, 1)
            }));
            v.push(("nan", replace_numbers(good, "nan")));
            v.push(("short rows", good.replace(",0", "")));
            v.push(("extra fields", good.replace('\n', ",1,2,3\n")));
            v.push(("tabs", good.replace(',', "\t")));
        }
        Slot::Cell => {
            v.push(("log is a folder", format!("{good}[log]\npath = \"/tmp\"\n")));
            v.push((
                "log is /dev/null",
                format!("{good}[log]\npath = \"/dev/null\"\n"),
            ));
            v.push((
                "log is itself",
                format!("{good}[log]\npath = \"cell.toml\"\n"),
            ));
            v.push((
                "log under a file",
                format!("{good}[log]\npath = \"cell.toml/log.csv\"\n"),
            ));
            v.push((
                "rate nan",
                good.replace("realtime = false", "realtime = false\nrate_hz = nan"),
            ));
            v.push((
                "rate 1e300",
                good.replace("realtime = false", "realtime = false\nrate_hz = 1e300"),
            ));
            v.push((
                "peer any",
                good.replace(
                    "timeout_s = 0.2\n[sensor]",
                    "timeout_s = 0.2\npeer = \"0.0.0.0:0\"\n[sensor]",
                ),
            ));
            v.push(("bind any", good.replace("127.0.0.1:1", "0.0.0.0:1")));
            v.push((
                "model fifo",
                good.replace("file = \"tx200\"", "file = \"/dev/zero\""),
            ));
            v.push(("unknown section", format!("{good}[robots]\nkind = 1\n")));
        }
        _ => {}
    }
    v
}

fn drop_key(text: &str, key: &str) -> String {
    text.lines()
        .filter(|l| {
            let t = l.trim_start();
            !(t.starts_with(&format!("{key} =")) || t.starts_with(&format!("{key}=")))
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Numeric abuse on the command line, with the flag each must name.
const NUMERIC_CASES: &[(&[&str], &str)] = &[
    (
        &["pose", "--robot", "tx200", "--q-deg", "1e300,0,0,0,0,0"],
        "--q-deg",
    ),
    (
        &["pose", "--robot", "tx200", "--q-deg", "-1e6,0,0,0,0,0"],
        "--q-deg",
    ),
    (
        &["pose", "--robot", "tx200", "--q-rad", "nan,0,0,0,0,0"],
        "--q-rad",
    ),
    (&["pose", "--robot", "tx200", "--q-deg", "0,0,0"], "joint"),
    (
        &["deflect", "--robot", "tx200", "--q-deg", "0,0,0,0,0,1e300"],
        "--q-deg",
    ),
    (
        &[
            "deflect",
            "--robot",
            "tx200",
            "--q-deg",
            "0,-90,90,0,0,0",
            "--wrench",
            "1e300,0,0,0,0,0",
        ],
        "--wrench",
    ),
    (
        &[
            "deflect",
            "--robot",
            "tx200",
            "--q-deg",
            "0,-90,90,0,0,0",
            "--wrench",
            "0,0,inf,0,0,0",
        ],
        "--wrench",
    ),
    (
        &[
            "ik",
            "--robot",
            "tx200",
            "--xyz-mm",
            "1500,0,500",
            "--rpy-deg",
            "180,0,0",
            "--seed-deg",
            "1e300,0,0,0,0,0",
        ],
        "--seed-deg",
    ),
    (
        &[
            "ik",
            "--robot",
            "tx200",
            "--xyz-mm",
            "nan,0,500",
            "--rpy-deg",
            "180,0,0",
        ],
        "--xyz-mm",
    ),
    (
        &[
            "map",
            "--robot",
            "tx200",
            "--wrench",
            "0,0,-1e300,0,0,0",
            "--out",
            "{OUT}",
        ],
        "--wrench",
    ),
    (
        &[
            "compensate",
            "--robot",
            "tx200",
            "--path",
            "{G:gcode}",
            "--seed-deg",
            "1e300,0,0,0,0,0",
            "--out",
            "{OUT}",
        ],
        "--seed-deg",
    ),
    (
        &[
            "compensate",
            "--robot",
            "tx200",
            "--path",
            "{G:gcode}",
            "--length-mm",
            "1e-300",
            "--out",
            "{OUT}",
        ],
        "--length-mm",
    ),
    (
        &[
            "compensate",
            "--robot",
            "tx200",
            "--path",
            "{G:gcode}",
            "--length-mm",
            "nan",
            "--out",
            "{OUT}",
        ],
        "--length-mm",
    ),
    (
        &["run", "--config", "{G:cell}", "--duration-s", "nan"],
        "--duration-s",
    ),
];

/// The sweep; `full`: every case, else the fixed subset run by `cargo test`.
fn sweep(full: bool) -> Tally {
    let fx = Fixture::new(if full { "full" } else { "fast" });
    let mut tally = Tally::default();
    let mut n = 0usize;
    // Bad files in every input slot.
    for (t, template) in INPUT_TEMPLATES.iter().enumerate() {
        for (b, bad) in BAD_INPUTS.iter().enumerate() {
            if !full && b != t % BAD_INPUTS.len() && b != (t + 7) % BAD_INPUTS.len() {
                continue;
            }
            n += 1;
            // An empty settings file is every default: a valid file, not a bad one.
            if matches!(bad, BadInput::Empty)
                && matches!(template.slot, Slot::Twin | Slot::ProgramConfig)
            {
                continue;
            }
            let input = make_bad(&fx, *bad, &fx.good(template.slot), n);
            let out = fx.dir.join("bad").join(format!("o{n}"));
            let args = fill(&fx, template.args, &input, &out, n);
            let label = format!("{} = {bad:?}", template.name);
            run_case(&fx, &mut tally, &label, &args, &names_of(&input));
        }
    }
    // Bad contents in robot, data and cell slots.
    for (t, template) in INPUT_TEMPLATES.iter().enumerate() {
        let good = std::fs::read_to_string(fx.good(template.slot)).unwrap_or_default();
        let variants = content_variants(template.slot, &good)
            .into_iter()
            // `cell --sim` plays the robot: it reads no log, model or peer from the cell file.
            .filter(|_| !template.name.starts_with("cell"))
            // One reading, or one repeated, is a fine plan or validation set; only a
            // calibration must refuse it.
            .filter(|(what, _)| {
                template.name.starts_with("calibrate")
                    || !matches!(*what, "one row" | "500 identical rows")
            });
        for (v, (what, text)) in variants.enumerate() {
            if !full && v != t % 5 {
                continue;
            }
            n += 1;
            let name = fx.good(template.slot);
            let ext = name
                .extension()
                .map(|e| e.to_string_lossy().into_owned())
                .unwrap_or_default();
            // Cell files name their log relative to themselves: each in its own folder.
            let folder = fx.dir.join("bad").join(format!("c{n}"));
            std::fs::create_dir_all(&folder).unwrap();
            let input = if template.slot == Slot::Cell {
                folder.join("cell.toml")
            } else {
                folder.join(format!("file.{ext}"))
            };
            std::fs::write(&input, &text).unwrap();
            let out = fx.dir.join("bad").join(format!("o{n}"));
            let args = fill(&fx, template.args, &input, &out, n);
            let label = format!("{} = {what}", template.name);
            let mut needles = names_of(&input);
            needles.push("[log]".into());
            // A robot file naming a special file as its URDF: the message names that file.
            needles.push("/dev/zero".into());
            run_case(&fx, &mut tally, &label, &args, &needles);
        }
    }
    // Bad outputs of every command.
    for (t, (flag, folder, template)) in OUTPUT_TEMPLATES.iter().enumerate() {
        for (b, bad) in BAD_OUTPUTS.iter().enumerate() {
            if !full && b != t % BAD_OUTPUTS.len() {
                continue;
            }
            n += 1;
            let Some(out) = make_bad_output(&fx, *bad, *folder, template, n) else {
                continue;
            };
            let args = fill(&fx, template, Path::new(""), &out, n);
            let label = format!("{flag} = {bad:?}");
            let mut needles = names_of(&out);
            needles.push(flag.to_string());
            run_case(&fx, &mut tally, &label, &args, &needles);
        }
    }
    // Numbers.
    for (args, flag) in NUMERIC_CASES {
        n += 1;
        let out = fx.dir.join("bad").join(format!("o{n}"));
        let args = fill(&fx, args, Path::new(""), &out, n);
        run_case(&fx, &mut tally, flag, &args, &[flag.to_string()]);
    }
    let _ = std::fs::remove_dir_all(
        fx.dir
            .join("..")
            .join(format!("deflex-hostile-logs-{}", std::process::id())),
    );
    tally
}

#[test]
fn hostile_sweep_subset() {
    let tally = sweep(false);
    eprintln!("hostile sweep (subset): {}", tally.report());
    assert!(tally.cases >= 80, "{}", tally.report());
    assert_eq!(tally.failures(), 0, "{}", tally.report());
}

#[test]
#[ignore = "the whole sweep (over 1,000 cases, minutes): scripts/hostile-sweep"]
fn hostile_sweep_full() {
    let tally = sweep(true);
    println!("hostile sweep (full): {}", tally.report());
    assert!(tally.cases >= 1000, "{}", tally.report());
    assert_eq!(tally.failures(), 0, "{}", tally.report());
}
