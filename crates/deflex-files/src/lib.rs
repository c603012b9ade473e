//! # deflex-files
//!
//! deflex's one file discipline, used by every command and by `deflex run`'s log.
//!
//! **Outputs** ([`output`], [`atomic`]) are written whole or not at all and never replace what
//! is not deflex's:
//!
//! * an output path that exists must be a regular file (for a file output) or a folder deflex
//!   wrote (for a folder output: it holds the marker file [`MARKER`]) or an empty folder;
//!   anything else (a device, a FIFO, a socket, a link to nothing, a foreign folder) is refused
//!   before anything is touched ([`check_output`]); a symbolic link is followed, its target
//!   checked and written, the link kept;
//! * an output that is one of the command's inputs (the same file by device and inode, not by
//!   name), or a folder output that holds one, is refused ([`check_output`], [`track_inputs`]);
//! * a file goes to a temporary sibling `.NAME.tmp-PID-N` and is renamed over the destination
//!   once complete and synced ([`AtomicFile`], [`write_atomic`], [`write_through`]);
//! * a folder is built in a temporary sibling `.NAME.tmp-PID-N` and swapped in with one atomic
//!   exchange of the two names (Linux `renameat2(RENAME_EXCHANGE)`), so the old result stays
//!   until the new one is complete, stays if the new one fails, and there is no instant at
//!   which the folder is missing ([`AtomicDir`]). Where the file system cannot exchange, the
//!   old folder is renamed to `.NAME.old-PID-N` first and the next run restores it if a kill
//!   came between the two renames;
//! * temporaries left by killed runs (the exact patterns above, of processes that no longer
//!   run) are removed by the next run that writes the same output; a folder output is written
//!   under a lock (`.NAME.lock`), so a second concurrent run on it is refused with the first
//!   one's process id; concurrent runs on one file output each rename a whole file in, and the
//!   last one stays.
//!
//! **Inputs** ([`input`]) are read with a cap on the bytes actually read (`Read::take`), not on
//! what the metadata says, and only from regular files: a device, a socket, a folder, a FIFO
//! or a pipe (a process substitution) is refused on the open descriptor, opened without
//! blocking so that a FIFO cannot make deflex wait ([`read_bounded`]). A command-line tool calls
//! [`track_inputs`] so that an output naming a file it read is refused.
//!
//! **Errors** shared by every reader and writer of files ([`errors`]): an I/O failure on a named
//! file ([`FileIoError`]) and a file larger than its reader accepts ([`FileTooLarge`]), defined
//! here once and held by the crates' error enums as a variant's payload.
//!
//! **Messages** that show user text (labels, paths) escape control characters ([`shown`]).
//!
//! **CSV text** built in memory by the formats' writers ([`csv_text`]).

#![warn(missing_docs)]

pub mod atomic;
mod csv_text;
pub mod errors;
pub mod input;
pub mod output;
mod shown;

pub use atomic::{AtomicDir, AtomicFile, write_atomic, write_through};
pub use csv_text::csv_text;
pub use errors::{FileIoError, FileTooLarge};
pub use input::{
    FileKind, InputError, InputProblem, open_input, read_bounded, read_bounded_bytes, track_inputs,
};
pub use output::{
    MARKER, OutputError, OutputKind, OutputProblem, check_output, check_output_flag, problem_of,
};
pub use shown::{shown, shown_path, shown_text};
