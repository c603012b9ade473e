//! The shared file errors ([`deflex_files::FileIoError`], [`deflex_files::FileTooLarge`]) and
//! how a bounded read's failure becomes them ([`deflex_files::InputError::reported_as`]).

use super::scratch;
use deflex_files::{FileIoError, FileTooLarge, read_bounded};
use std::error::Error as _;
use std::io;

#[derive(Debug, thiserror::Error)]
enum ReaderError {
    #[error(transparent)]
    Io(#[from] FileIoError),
    #[error(transparent)]
    TooLarge(#[from] FileTooLarge),
}

#[test]
fn an_io_error_names_the_file_escaped_with_an_optional_context() {
    let e = FileIoError::new("data/run.csv", io::Error::other("disk on fire"));
    assert_eq!(e.to_string(), "data/run.csv: disk on fire");
    assert_eq!(e.path(), std::path::Path::new("data/run.csv"));
    assert!(e.source().is_some(), "the system's error is the source");
    let e = e.context("cannot start the recording");
    assert_eq!(
        e.to_string(),
        "data/run.csv: cannot start the recording: disk on fire"
    );
    let e = FileIoError::other("a\u{1b}[2J.csv", io::ErrorKind::InvalidInput, "refused");
    assert_eq!(e.to_string(), "a\\u{1b}[2J.csv: refused");
    assert_eq!(e.source.kind(), io::ErrorKind::InvalidInput);
}

#[test]
fn a_file_too_large_says_what_its_reader_reads() {
    let e = FileTooLarge::new("m.csv", "a measurement file", 10, 11);
    assert_eq!(
        e.to_string(),
        "m.csv: more than the 10 bytes a measurement file may have (stopped reading after 11)"
    );
    assert_eq!(
        FileTooLarge::new("r\n.toml", "a robot description", 4, 5).to_string(),
        "r\\n.toml: more than the 4 bytes a robot description may have (stopped reading after 5)"
    );
}

#[test]
fn a_bounded_read_is_reported_as_the_readers_error() {
    let dir = scratch("reported");
    let path = dir.join("notes.txt");
    std::fs::write(&path, "0123456789").unwrap();
    let e = read_bounded(&path, 9)
        .map_err(|e| e.reported_as::<ReaderError>("a notes file"))
        .unwrap_err();
    match &e {
        ReaderError::TooLarge(t) => {
            assert_eq!((t.limit, t.read, t.what), (9, 10, "a notes file"));
            assert_eq!(t.path, path);
        }
        other => panic!("expected too large, got {other:?}"),
    }
    assert_eq!(
        e.to_string(),
        format!(
            "{}: more than the 9 bytes a notes file may have (stopped reading after 10)",
            path.display()
        )
    );
    // Missing: the system's error, naming the file.
    let missing = dir.join("missing.txt");
    let e = read_bounded(&missing, 9)
        .map_err(|e| e.reported_as::<ReaderError>("a notes file"))
        .unwrap_err();
    match &e {
        ReaderError::Io(io) => {
            assert_eq!(io.path, missing);
            assert_eq!(io.source.kind(), io::ErrorKind::NotFound);
        }
        other => panic!("expected an I/O error, got {other:?}"),
    }
    // Refused (a folder): the refusal inside the I/O error, as `into_io` gives it.
    let e = read_bounded(&dir, 9)
        .map_err(|e| e.reported_as::<ReaderError>("a notes file"))
        .unwrap_err();
    let ReaderError::Io(io) = &e else {
        panic!("expected an I/O error, got {e:?}")
    };
    assert_eq!(io.source.kind(), io::ErrorKind::InvalidData);
    assert_eq!(
        e.to_string(),
        read_bounded(&dir, 9).unwrap_err().to_string(),
        "the same message as the file discipline's own error"
    );
    std::fs::remove_dir_all(dir).unwrap();
}
