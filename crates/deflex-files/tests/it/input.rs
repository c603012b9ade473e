//! Bounded inputs ([`deflex_files::input`]): only regular files, capped by what is read.

use crate::scratch;
use deflex_files::{FileKind, InputError, InputProblem, read_bounded};
use std::path::Path;

#[test]
fn devices_folders_and_fifos_are_refused_without_reading_or_waiting() {
    for (path, kind) in [
        ("/dev/zero", FileKind::CharDevice),
        ("/dev/urandom", FileKind::CharDevice),
        ("/dev/null", FileKind::CharDevice),
        ("/", FileKind::Folder),
    ] {
        match read_bounded(Path::new(path), 10) {
            Err(e) => assert_eq!(
                e.problem(),
                Some(&InputProblem::NotAFile { kind }),
                "{path}"
            ),
            Ok(text) => panic!("{path}: read {text:?}"),
        }
    }
    let dir = scratch("fifo-in");
    let fifo = dir.join("robot.urdf");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: mkfifo with a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let e = read_bounded(&fifo, 10).unwrap_err();
    assert_eq!(
        e.problem(),
        Some(&InputProblem::NotAFile {
            kind: FileKind::Fifo
        }),
        "{e}"
    );
    assert!(e.to_string().contains("robot.urdf"), "{e}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_pipe_is_refused_and_a_regular_file_is_bounded_by_what_is_read() {
    let mut fds = [0; 2];
    // SAFETY: pipe with a valid two-element array.
    assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
    let e = read_bounded(Path::new(&format!("/proc/self/fd/{}", fds[0])), 10).unwrap_err();
    assert_eq!(
        e.problem(),
        Some(&InputProblem::NotAFile {
            kind: FileKind::Fifo
        }),
        "{e}"
    );
    // SAFETY: closing the two descriptors pipe returned.
    unsafe {
        libc::close(fds[0]);
        libc::close(fds[1]);
    }
    let dir = scratch("bounded");
    let path = dir.join("data.csv");
    std::fs::write(&path, "0123456789").unwrap();
    assert_eq!(read_bounded(&path, 10).unwrap(), "0123456789");
    let e = read_bounded(&path, 9).unwrap_err();
    assert_eq!(
        e.problem(),
        Some(&InputProblem::TooLarge { limit: 9, read: 10 })
    );
    std::fs::write(&path, [0x41, 0xff, 0x42]).unwrap();
    let e = read_bounded(&path, 10).unwrap_err();
    assert_eq!(e.problem(), Some(&InputProblem::NotText { offset: 1 }));
    assert!(matches!(
        read_bounded(&dir.join("missing"), 10),
        Err(InputError::Io { .. })
    ));
    std::fs::remove_dir_all(dir).unwrap();
}
