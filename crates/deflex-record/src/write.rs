//! Writing: [`McapSink`] turns cycle samples into the channels of [`crate::channels`]
//! ([`crate::McapRecorder`] runs one on its own thread).

use crate::channels as ch;
use crate::{RecordError, SessionRecord};
use deflex_telemetry::ros::cycle::{self, CycleMessages, DiagnosticsPacer, seconds_to_ns};
use deflex_telemetry::ros::{
    DiagnosticArrayMsg, JointStateMsg, PoseStampedMsg, RosMessage, TimeMsg, TwistStampedMsg,
    Vector3StampedMsg, WrenchStampedMsg,
};
use deflex_telemetry::{CycleSample, SessionInfo};
use mcap::records::MessageHeader;
use mcap::write::NoSeek;
use std::collections::BTreeMap;
use std::io::Write;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// Smallest file size cap [`RecordOptions::max_bytes`] accepts (bytes).
pub const MIN_MAX_BYTES: u64 = 16 << 20;
/// Default file size cap (bytes): 8 GiB, about 30 h of a 100 Hz session.
pub const DEFAULT_MAX_BYTES: u64 = 8 << 30;
/// Uncompressed chunk size (bytes): the most the writer holds in memory before writing.
pub const CHUNK_BYTES: u64 = 1 << 20;

/// How a recording is written.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordOptions {
    /// The file is closed (and the rest of the session counted as not recorded) before it would
    /// grow past this many bytes; at least [`MIN_MAX_BYTES`].
    pub max_bytes: u64,
    /// Period of the `/diagnostics` messages between changes of state (s).
    pub diagnostics_period_s: f64,
    /// Wall-clock time of session time 0 (ns since the Unix epoch); `None`: now, when the
    /// recording starts, minus the first sample's session time.
    pub start_unix_ns: Option<u64>,
    /// Compress chunks with LZ4 (about 3× smaller; every reader named in the README reads it).
    pub compress: bool,
}

impl Default for RecordOptions {
    fn default() -> Self {
        RecordOptions {
            max_bytes: DEFAULT_MAX_BYTES,
            diagnostics_period_s: 0.1,
            start_unix_ns: None,
            compress: true,
        }
    }
}

/// What a recording holds.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RecordStats {
    /// Cycles recorded.
    pub recorded: u64,
    /// Cycles not recorded because the file reached its size cap.
    pub after_cap: u64,
    /// MCAP messages written.
    pub messages: u64,
    /// Bytes written to the file.
    pub bytes: u64,
}

/// Counts the bytes that reach the underlying writer.
struct Counting<W> {
    inner: W,
    bytes: Arc<AtomicU64>,
}

impl<W: Write> Write for Counting<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.bytes.fetch_add(n as u64, Ordering::Relaxed);
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

struct Channels {
    joint_states: u16,
    wrench_raw: u16,
    wrench_sensor: u16,
    wrench_tcp: u16,
    tcp_pose: u16,
    program_pose: u16,
    deflection: u16,
    correction: u16,
    error: u16,
    feedforward: u16,
    path_error: u16,
    diagnostics: u16,
}

/// Writes cycle samples as MCAP messages into any writer (synchronously: the twin can call it in
/// its own loop and lose nothing; the runtime uses [`crate::McapRecorder`]).
pub struct McapSink<W: Write> {
    writer: mcap::Writer<NoSeek<Counting<W>>>,
    channels: Channels,
    info: SessionInfo,
    options: RecordOptions,
    target: String,
    epoch_ns: Option<u64>,
    stats: RecordStats,
    capped: bool,
    pacer: DiagnosticsPacer,
    recorder_lost: u64,
    bytes: Arc<AtomicU64>,
}

fn schema<T: RosMessage>(
    w: &mut mcap::Writer<impl Write + std::io::Seek>,
) -> mcap::McapResult<u16> {
    w.add_schema(T::NAME, "ros2msg", T::DEFINITION.as_bytes())
}

impl<W: Write> McapSink<W> {
    /// Starts a recording into `out`; `target` names it in errors (the file path).
    pub fn new(
        out: W,
        target: impl Into<String>,
        info: &SessionInfo,
        options: RecordOptions,
    ) -> Result<McapSink<W>, RecordError> {
        let target = target.into();
        let options = RecordOptions {
            max_bytes: options.max_bytes.max(MIN_MAX_BYTES),
            ..options
        };
        let mcap_err = |e: mcap::McapError| RecordError::from_mcap(&target, 0, e);
        let bytes = Arc::new(AtomicU64::new(0));
        let compression = options.compress.then_some(mcap::Compression::Lz4);
        let mut writer = mcap::WriteOptions::new()
            .profile("ros2")
            .library(concat!("deflex-record ", env!("CARGO_PKG_VERSION")))
            .compression(compression)
            .chunk_size(Some(CHUNK_BYTES))
            .disable_seeking(true)
            .create(NoSeek::new(Counting {
                inner: out,
                bytes: bytes.clone(),
            }))
            .map_err(mcap_err)?;
        let empty = BTreeMap::new();
        let channel = |w: &mut mcap::Writer<_>, schema: u16, topic: &str| {
            w.add_channel(schema, topic, "cdr", &empty)
        };
        let joint = schema::<JointStateMsg>(&mut writer).map_err(mcap_err)?;
        let wrench = schema::<WrenchStampedMsg>(&mut writer).map_err(mcap_err)?;
        let pose = schema::<PoseStampedMsg>(&mut writer).map_err(mcap_err)?;
        let twist = schema::<TwistStampedMsg>(&mut writer).map_err(mcap_err)?;
        let vector = schema::<Vector3StampedMsg>(&mut writer).map_err(mcap_err)?;
        let diag = schema::<DiagnosticArrayMsg>(&mut writer).map_err(mcap_err)?;
        let channels = (|| {
            Ok::<_, mcap::McapError>(Channels {
                joint_states: channel(&mut writer, joint, ch::JOINT_STATES)?,
                wrench_raw: channel(&mut writer, wrench, ch::WRENCH_RAW)?,
                wrench_sensor: channel(&mut writer, wrench, ch::WRENCH_SENSOR)?,
                wrench_tcp: channel(&mut writer, wrench, ch::WRENCH_TCP)?,
                tcp_pose: channel(&mut writer, pose, ch::TCP_POSE)?,
                program_pose: channel(&mut writer, pose, ch::PROGRAM_POSE)?,
                deflection: channel(&mut writer, twist, ch::DEFLECTION)?,
                correction: channel(&mut writer, twist, ch::CORRECTION)?,
                error: channel(&mut writer, twist, ch::ERROR)?,
                feedforward: channel(&mut writer, twist, ch::FEEDFORWARD)?,
                path_error: channel(&mut writer, vector, ch::PATH_ERROR)?,
                diagnostics: channel(&mut writer, diag, ch::DIAGNOSTICS)?,
            })
        })()
        .map_err(mcap_err)?;
        Ok(McapSink {
            pacer: DiagnosticsPacer::new(options.diagnostics_period_s),
            writer,
            channels,
            info: info.clone(),
            options,
            target,
            epoch_ns: None,
            stats: RecordStats::default(),
            capped: false,
            recorder_lost: 0,
            bytes,
        })
    }

    /// What was written so far.
    pub fn stats(&self) -> &RecordStats {
        &self.stats
    }

    /// True once the size cap was reached (later samples are counted, not written).
    pub fn is_capped(&self) -> bool {
        self.capped
    }

    /// Tells the sink how many samples its feed lost (reported in `/diagnostics`).
    pub fn set_lost(&mut self, lost: u64) {
        self.recorder_lost = lost;
    }

    /// Bytes written to the output so far.
    pub fn bytes(&self) -> u64 {
        self.bytes.load(Ordering::Relaxed)
    }

    /// Records one cycle. Returns false when it was not written because the file is at its cap.
    pub fn write(&mut self, s: &CycleSample) -> Result<bool, RecordError> {
        if self.capped {
            self.stats.after_cap += 1;
            return Ok(false);
        }
        // Keep room for the chunk being built, its index and the summary (chunk indexes grow
        // with the file: ≈ 0.1 % of it).
        let reserve = 2 * CHUNK_BYTES + (4 << 20) + self.bytes() / 1000;
        if self.bytes() + reserve > self.options.max_bytes {
            self.capped = true;
            self.stats.after_cap += 1;
            return Ok(false);
        }
        let epoch = *self.epoch_ns.get_or_insert_with(|| {
            self.options.start_unix_ns.unwrap_or_else(|| {
                let now = std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map_or(0, |d| d.as_nanos() as u64);
                now.saturating_sub(seconds_to_ns(s.time_s))
            })
        });
        if self.stats.recorded == 0 {
            self.write_session(epoch)?;
        }
        let t_ns = epoch.saturating_add(seconds_to_ns(s.time_s));
        let header = MessageHeader {
            channel_id: 0,
            sequence: s.cycle as u32,
            log_time: t_ns,
            publish_time: t_ns,
        };
        let stamp = TimeMsg::from_nanos(t_ns);
        let m = CycleMessages::new(&self.info, s, stamp);
        let c = &self.channels;
        let ids = (c.joint_states, c.wrench_raw, c.wrench_sensor, c.wrench_tcp);
        self.put(ids.0, &header, &m.joint_states)?;
        self.put(ids.1, &header, &m.wrench_raw)?;
        self.put(ids.2, &header, &m.wrench_sensor)?;
        self.put(ids.3, &header, &m.wrench_tcp)?;
        let c = &self.channels;
        let ids = (c.tcp_pose, c.program_pose);
        self.put(ids.0, &header, &m.tcp_pose)?;
        self.put(ids.1, &header, &m.program_pose)?;
        let c = &self.channels;
        let ids = (c.deflection, c.correction, c.error, c.feedforward);
        self.put(ids.0, &header, &m.deflection)?;
        self.put(ids.1, &header, &m.correction)?;
        self.put(ids.2, &header, &m.error)?;
        self.put(ids.3, &header, &m.feedforward)?;
        if let Some(path_error) = &m.path_error {
            self.put(self.channels.path_error, &header, path_error)?;
        }
        if self.pacer.due(s) {
            let extra = [(ch::diag::RECORDER_LOST, self.recorder_lost.to_string())];
            let msg = cycle::diagnostics(&self.info, s, stamp, &extra);
            self.put(self.channels.diagnostics, &header, &msg)?;
        }
        self.stats.recorded += 1;
        Ok(true)
    }

    fn write_session(&mut self, epoch: u64) -> Result<(), RecordError> {
        let record = SessionRecord::new(&self.info, epoch);
        let json = serde_json::to_vec(&record).map_err(|e| RecordError::Mcap {
            path: self.target.clone(),
            message: format!("session description: {e}"),
        })?;
        let target = self.target.clone();
        let bytes = self.bytes();
        let err = |e| RecordError::from_mcap(&target, bytes, e);
        let schema = self
            .writer
            .add_schema(
                "deflex.Session",
                "jsonschema",
                crate::session::SESSION_JSON_SCHEMA.as_bytes(),
            )
            .map_err(err)?;
        let id = self
            .writer
            .add_channel(schema, ch::SESSION, "json", &BTreeMap::new())
            .map_err(err)?;
        self.writer
            .write_to_known_channel(
                &MessageHeader {
                    channel_id: id,
                    sequence: 0,
                    log_time: epoch,
                    publish_time: epoch,
                },
                &json,
            )
            .map_err(err)?;
        self.writer
            .write_metadata(&mcap::records::Metadata {
                name: "deflex".into(),
                metadata: record.to_map(),
            })
            .map_err(err)?;
        self.stats.messages += 1;
        Ok(())
    }

    fn put<T: RosMessage>(
        &mut self,
        channel_id: u16,
        header: &MessageHeader,
        msg: &T,
    ) -> Result<(), RecordError> {
        let data = deflex_telemetry::ros::encode(msg).map_err(|e| RecordError::Encode {
            path: self.target.clone(),
            source: e,
        })?;
        let header = MessageHeader {
            channel_id,
            ..*header
        };
        let result = self.writer.write_to_known_channel(&header, &data);
        self.stats.bytes = self.bytes();
        result.map_err(|e| RecordError::from_mcap(&self.target, self.stats.bytes, e))?;
        self.stats.messages += 1;
        Ok(())
    }

    /// Writes the summary and returns the writer and what was recorded.
    pub fn finish(mut self) -> Result<(W, RecordStats), RecordError> {
        let result = self.writer.finish();
        self.stats.bytes = self.bytes();
        result.map_err(|e| RecordError::from_mcap(&self.target, self.stats.bytes, e))?;
        let counting = self.writer.into_inner().into_inner();
        Ok((counting.inner, self.stats))
    }
}
