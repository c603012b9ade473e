//! [`McapRecorder`]: an [`McapSink`] on its own thread, fed by a telemetry [`Subscriber`], into
//! a file written aside and renamed at the end.

use crate::{McapSink, RecordError, RecordOptions, RecordStats};
use deflex_files::FileIoError;
use deflex_telemetry::{Broadcast, CycleSample, SessionInfo, Subscriber};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

/// What a finished [`McapRecorder`] did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RecordReport {
    /// The file (at its destination).
    pub path: PathBuf,
    /// What was written.
    pub stats: RecordStats,
    /// Samples the recorder lost: overwritten in the telemetry ring before it read them (the
    /// publisher never waits for the recorder).
    pub lost: u64,
}

/// How often the recorder thread looks for new samples when it has caught up.
const POLL: Duration = Duration::from_millis(20);

/// A recording on its own thread: drains a [`Subscriber`] into an MCAP file written aside
/// (`.NAME.tmp-…`) and renamed over `path` by [`McapRecorder::finish`]; a failed recording
/// leaves whatever was at `path` untouched.
///
/// ```no_run
/// # use std::sync::Arc;
/// use deflex_telemetry::{broadcast, CycleSample, SessionInfo, StreamSource};
/// let (mut publisher, ring) = broadcast::<CycleSample>(4096);
/// let info = Arc::new(SessionInfo::new(StreamSource::Runtime, "tx200", vec!["j1".into()]));
/// let recorder = deflex_record::McapRecorder::spawn("run.mcap", &ring, info).unwrap();
/// // … the control thread publishes one sample per cycle …
/// publisher.publish(&CycleSample::default());
/// drop(publisher); // the session ends
/// let report = recorder.finish().unwrap();
/// eprintln!("{} cycles recorded, {} lost", report.stats.recorded, report.lost);
/// ```
pub struct McapRecorder {
    path: PathBuf,
    stop: Arc<AtomicBool>,
    commit: Arc<AtomicBool>,
    handle: JoinHandle<Result<RecordReport, RecordError>>,
}

impl McapRecorder {
    /// Records every sample published on `ring` from now on into `path`, with default options.
    pub fn spawn(
        path: impl AsRef<Path>,
        ring: &Arc<Broadcast<CycleSample>>,
        info: Arc<SessionInfo>,
    ) -> Result<McapRecorder, RecordError> {
        Self::spawn_with(path, ring.subscribe(), info, RecordOptions::default())
    }

    /// Records the samples of `subscriber` into `path` with `options`.
    pub fn spawn_with(
        path: impl AsRef<Path>,
        mut subscriber: Subscriber<CycleSample>,
        info: Arc<SessionInfo>,
        options: RecordOptions,
    ) -> Result<McapRecorder, RecordError> {
        let path = path.as_ref().to_path_buf();
        let name = path.display().to_string();
        let cannot_start = |e| {
            RecordError::Create(FileIoError::new(&path, e).context("cannot start the recording"))
        };
        let file = deflex_files::AtomicFile::create(&path).map_err(cannot_start)?;
        let mut sink = McapSink::new(file, name.clone(), &info, options)?;
        let stop = Arc::new(AtomicBool::new(false));
        let stop_flag = stop.clone();
        let commit = Arc::new(AtomicBool::new(true));
        let commit_flag = commit.clone();
        let report_path = path.clone();
        let handle = std::thread::Builder::new()
            .name("deflex-mcap".into())
            .spawn(move || {
                loop {
                    // Read the flag before draining: whatever was published before `finish`
                    // set it is drained below.
                    let stopping = stop_flag.load(Ordering::Acquire);
                    let mut failed = None;
                    subscriber.drain(|s| {
                        if failed.is_none()
                            && let Err(e) = sink.write(s)
                        {
                            failed = Some(e);
                        }
                    });
                    sink.set_lost(subscriber.lost());
                    if let Some(e) = failed {
                        return Err(e);
                    }
                    if stopping {
                        break;
                    }
                    // Once the stream has ended there is nothing more to read: wait for
                    // `finish` to say whether the file is kept.
                    std::thread::sleep(if subscriber.is_finished() {
                        POLL * 2
                    } else {
                        POLL
                    });
                }
                let lost = subscriber.lost();
                let (file, stats) = sink.finish()?;
                if commit_flag.load(Ordering::Acquire) {
                    file.commit()
                        .map_err(|e| RecordError::from_io(&name, stats.bytes, e))?;
                }
                Ok(RecordReport {
                    path: report_path,
                    stats,
                    lost,
                })
            })
            .map_err(cannot_start)?;
        Ok(McapRecorder {
            path,
            stop,
            commit,
            handle,
        })
    }

    /// The destination.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// True when the recorder thread has ended early (a write error); it otherwise runs until
    /// [`Self::finish`].
    pub fn is_finished(&self) -> bool {
        self.handle.is_finished()
    }

    /// Records what was published up to now, closes the file and renames it into place. Call it
    /// once the session has ended (or to stop recording early).
    pub fn finish(self) -> Result<RecordReport, RecordError> {
        self.finish_with(true)
    }

    /// [`Self::finish`], renaming the file into place only when `commit` (a failed session
    /// discards its recording and leaves what was at the path whole, as it does its CSV log).
    pub fn finish_with(self, commit: bool) -> Result<RecordReport, RecordError> {
        self.commit.store(commit, Ordering::Release);
        self.stop.store(true, Ordering::Release);
        self.handle.join().map_err(|_| RecordError::Panicked {
            path: self.path.display().to_string(),
        })?
    }
}
