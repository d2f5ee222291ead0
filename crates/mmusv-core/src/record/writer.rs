//! The MCAP file itself: creation under a `.partial` name, channels created on first use, per-channel sequence
//! numbers, metadata and attachments, and the rename into place on [`Recorder::finish`].
//!
//! The first frame's channels come first, in a chunk of their own: the messages of the first log time are held
//! until a message of another time (or metadata, an attachment, the end) arrives, then every schema and channel
//! they use is written and that chunk closed before them. A reader without the summary (a killed run's
//! `.partial`, a copy cut short) learns the channels from that small chunk, so a damaged chunk of frame 0 loses
//! its own messages alone; when the channels lay beside frame 0's first messages, it lost every frame after them.
//!
//! Deterministic: no wall clock is read; log and publish times are the simulation times the caller gives;
//! zstd runs single-threaded with a fixed level (`ZSTD_LEVEL`), so the same calls give the same bytes.

use crate::error::{MmusvError, Result};
use foxglove::Encode;
use mcap::records::{MessageHeader, Metadata};
use mcap::{Attachment, WriteOptions, Writer};
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// zstd level of the chunks: 1, the fastest of the regular levels. On `port_entry` (2-core AMD EPYC, 2026-11-27,
/// two alternating runs each) level 1 wrote 935.9 MB at 1.36–1.39 frames/s (70.6–71.8 CPU s), level 3 888.7 MB at
/// 1.33 (73.4–73.7 CPU s): 5 % more disk for 3 % less CPU, most of the data being PNG images and radar returns
/// that neither level shrinks much.
const ZSTD_LEVEL: u32 = 1;

/// Target uncompressed size of one zstd chunk.
const CHUNK_BYTES: u64 = 4 << 20;

/// The most bytes of first-time messages held back (see the module's header): past it they are written, so a
/// caller that writes everything at one log time does not keep its whole recording in memory.
const HOLD_BYTES: usize = 256 << 20;

/// What [`Recorder::finish`] reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RecordSummary {
    /// Where the finished file now lies.
    pub path: PathBuf,
    /// Messages written, all channels.
    pub messages: u64,
    /// Channels (topics) created.
    pub channels: u32,
    /// Size of the finished file, bytes.
    pub bytes: u64,
}

/// A message serialised for its topic, ready for [`Recorder::write_message`]; needs no recorder to build, so
/// it can be made outside the recorder's lock.
#[derive(Clone)]
pub struct EncodedMessage {
    /// The topic it goes to.
    pub topic: String,
    /// Its schema (name, encoding, descriptor).
    pub schema: foxglove::Schema,
    /// Its message encoding (`protobuf`).
    pub message_encoding: String,
    /// The serialised message.
    pub data: Vec<u8>,
}

impl std::fmt::Debug for EncodedMessage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EncodedMessage")
            .field("topic", &self.topic)
            .field("schema", &self.schema.name)
            .field("bytes", &self.data.len())
            .finish()
    }
}

impl EncodedMessage {
    /// Serialises `message` for `topic`.
    pub fn encode<M: Encode>(topic: &str, message: &M) -> Result<Self> {
        let mut data = Vec::with_capacity(message.encoded_len().unwrap_or(1024));
        message
            .encode(&mut data)
            .map_err(|e| MmusvError::input(topic.to_string(), format!("message could not be encoded: {e}")))?;
        let Some(schema) = M::get_schema() else {
            return Err(MmusvError::input(topic.to_string(), "message type has no schema"));
        };
        Ok(Self { topic: topic.to_string(), schema, message_encoding: M::get_message_encoding(), data })
    }
}

/// A channel created on first use of its topic.
struct Slot {
    /// The channel's id; `None` while its first messages are held and it is not yet written.
    id: Option<u16>,
    schema: String,
    next_sequence: u32,
}

/// A message of the first log time, held until its channels are written (see the module's header).
struct Held {
    topic: String,
    log_time: u64,
    sequence: u32,
    data: Vec<u8>,
}

/// Where the holding of the first log time's messages stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Hold {
    /// No message yet: the first one starts the holding.
    Ready,
    /// Holding the messages of `log_time`, `bytes` of them.
    Holding { log_time: u64, bytes: usize },
    /// Released: messages are written as they come.
    Done,
}

/// Streams messages into one MCAP file. Write under `<path>.partial`; [`finish`](Self::finish) completes the
/// file and renames it to `path`. Dropped without `finish`, it still completes the MCAP (readable, with
/// everything written) but leaves it under the `.partial` name, so an interrupted run never looks complete.
pub struct Recorder {
    writer: Option<Writer<BufWriter<File>>>,
    path: PathBuf,
    partial: PathBuf,
    channels: BTreeMap<String, Slot>,
    /// The held messages' channels not yet written, in the order of their first message.
    pending: Vec<(String, foxglove::Schema, String)>,
    held: Vec<Held>,
    hold: Hold,
    messages: u64,
    /// The reason of the first failed write: the MCAP writer refuses every write after one fails, with a
    /// message that no longer says why, so later errors repeat this one.
    first_failure: Option<String>,
}

impl std::fmt::Debug for Recorder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recorder")
            .field("path", &self.path)
            .field("channels", &self.channels.len())
            .field("messages", &self.messages)
            .finish_non_exhaustive()
    }
}

/// `<path>.partial`.
pub fn partial_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".partial");
    PathBuf::from(s)
}

fn io_err(path: &Path) -> impl Fn(std::io::Error) -> MmusvError + '_ {
    move |e| MmusvError::Io { path: path.display().to_string(), reason: e.to_string() }
}

/// The text of an MCAP error with its whole `source()` chain, so the operating system's reason (`No space left on
/// device (os error 28)`, `Read-only file system`) reaches the user rather than the crate's summary alone.
fn mcap_reason(e: &mcap::McapError) -> String {
    let mut reason = format!("MCAP write failed: {e}");
    let mut source = std::error::Error::source(e);
    while let Some(s) = source {
        let text = s.to_string();
        if !reason.contains(&text) {
            reason.push_str(": ");
            reason.push_str(&text);
        }
        source = s.source();
    }
    reason
}

fn mcap_err(path: &Path) -> impl Fn(mcap::McapError) -> MmusvError + '_ {
    move |e| MmusvError::Io { path: path.display().to_string(), reason: mcap_reason(&e) }
}

/// Opens `<path>.partial` for a new recording: locked (an exclusive advisory lock, held until the file closes),
/// then emptied. A `.partial` another recorder is writing — in this process or another — is refused, naming it:
/// two recorders on one name truncated each other's file, and the first `finish` renamed a damaged MCAP into
/// place. A file system without locks (`Unsupported`) is written unlocked, as before.
fn open_partial(partial: &Path) -> Result<File> {
    let file = std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(false) // emptied below, once this recorder holds the lock
        .open(partial)
        .map_err(io_err(partial))?;
    match file.try_lock() {
        Ok(()) => {}
        Err(std::fs::TryLockError::WouldBlock) => {
            return Err(MmusvError::Io {
                path: partial.display().to_string(),
                reason: "another recorder is writing this file (an open Recorder, or a run in another process); \
                         finish it first or record under another name"
                    .into(),
            })
        }
        Err(std::fs::TryLockError::Error(e)) if e.kind() == std::io::ErrorKind::Unsupported => {}
        Err(std::fs::TryLockError::Error(e)) => return Err(io_err(partial)(e)),
    }
    file.set_len(0).map_err(io_err(partial))?;
    Ok(file)
}

/// Completes the MCAP (summary, footer), flushes and syncs the file.
fn close(mut writer: Writer<BufWriter<File>>, partial: &Path) -> Result<()> {
    writer.finish().map_err(mcap_err(partial))?;
    let file = writer.into_inner().into_inner().map_err(|e| io_err(partial)(e.into_error()))?;
    file.sync_all().map_err(io_err(partial))
}

impl Recorder {
    /// Starts a recording that will be named `path`. An existing `path` is refused unless `overwrite`; it is
    /// then replaced only when [`finish`](Self::finish) succeeds. A stale `<path>.partial` is truncated; one that
    /// another recorder is still writing is refused (its `.partial` is locked while it is written).
    pub fn create(path: &Path, overwrite: bool) -> Result<Self> {
        if path.as_os_str().is_empty() {
            // An empty path would write `.partial` into the working directory and rename it to "" on finish.
            return Err(MmusvError::input("path", "is empty; give the recording's file name (e.g. run.mcap)"));
        }
        if path.is_dir() {
            return Err(MmusvError::Io { path: path.display().to_string(), reason: "is a directory".into() });
        }
        if path.exists() && !overwrite {
            return Err(MmusvError::Io {
                path: path.display().to_string(),
                reason: "the file already exists; pass overwrite=True (Python) or --overwrite (CLI) to replace it"
                    .into(),
            });
        }
        let partial = partial_path(path);
        let file = open_partial(&partial)?;
        let options = WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .compression_level(ZSTD_LEVEL)
            .compression_threads(0)
            .chunk_size(Some(CHUNK_BYTES))
            .profile("")
            .library(format!("mmusv {}", env!("CARGO_PKG_VERSION")));
        let writer = options.create(BufWriter::with_capacity(1 << 20, file)).map_err(mcap_err(&partial))?;
        Ok(Self {
            writer: Some(writer),
            path: path.to_path_buf(),
            partial,
            channels: BTreeMap::new(),
            pending: Vec::new(),
            held: Vec::new(),
            hold: Hold::Ready,
            messages: 0,
            first_failure: None,
        })
    }

    /// The final name of the recording.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The name written to until [`finish`](Self::finish).
    pub fn partial_path(&self) -> &Path {
        &self.partial
    }

    /// Messages written so far.
    pub fn messages(&self) -> u64 {
        self.messages
    }

    fn writer(&mut self) -> Result<&mut Writer<BufWriter<File>>> {
        let partial = &self.partial;
        self.writer.as_mut().ok_or_else(|| MmusvError::Io {
            path: partial.display().to_string(),
            reason: "the recording is already closed".into(),
        })
    }

    /// Encodes `message` and writes it on `topic` at simulation time `log_time_ns` (also the publish time).
    /// The channel and its schema are created on the first message of a topic; a topic keeps one schema.
    pub fn write<M: Encode>(&mut self, topic: &str, log_time_ns: u64, message: &M) -> Result<()> {
        self.write_message(log_time_ns, &EncodedMessage::encode(topic, message)?)
    }

    /// Writes a message encoded beforehand (e.g. on other threads, see [`super::batch`]): the same bytes as
    /// [`write`](Self::write) of the message it was encoded from.
    pub fn write_message(&mut self, log_time_ns: u64, message: &EncodedMessage) -> Result<()> {
        self.write_encoded(&message.topic, log_time_ns, &message.schema, &message.message_encoding, &message.data)
    }

    /// Writes already-encoded bytes with the given schema (used by [`write`](Self::write)).
    pub fn write_encoded(
        &mut self,
        topic: &str,
        log_time_ns: u64,
        schema: &foxglove::Schema,
        message_encoding: &str,
        data: &[u8],
    ) -> Result<()> {
        self.check_topic(topic, &schema.name)?;
        self.writer()?;
        match self.hold {
            Hold::Ready => self.hold = Hold::Holding { log_time: log_time_ns, bytes: 0 },
            Hold::Holding { log_time, bytes } if log_time != log_time_ns || bytes > HOLD_BYTES => self.release()?,
            _ => {}
        }
        let partial = self.partial.clone();
        let holding = matches!(self.hold, Hold::Holding { .. });
        if !self.channels.contains_key(topic) {
            let id = if holding {
                self.pending.push((topic.to_string(), schema.clone(), message_encoding.to_string()));
                None
            } else {
                Some(self.add_channel(topic, schema, message_encoding)?)
            };
            self.channels.insert(topic.to_string(), Slot { id, schema: schema.name.clone(), next_sequence: 0 });
        }
        let Some(slot) = self.channels.get_mut(topic) else { unreachable!("the channel was created above") };
        let sequence = slot.next_sequence;
        slot.next_sequence = slot.next_sequence.wrapping_add(1);
        if let Hold::Holding { bytes, .. } = &mut self.hold {
            *bytes += data.len();
            self.held.push(Held { topic: topic.to_string(), log_time: log_time_ns, sequence, data: data.to_vec() });
        } else {
            let Some(channel_id) = slot.id else { return Err(self.unwritten_channel(topic)) };
            let header = MessageHeader { channel_id, sequence, log_time: log_time_ns, publish_time: log_time_ns };
            let written = self.writer()?.write_to_known_channel(&header, data);
            written.map_err(|e| self.failed(&partial, &e))?;
        }
        self.messages += 1;
        Ok(())
    }

    /// The error of a message whose channel was never written (its declaration failed, and so did the recording).
    fn unwritten_channel(&self, topic: &str) -> MmusvError {
        let earlier = self.first_failure.as_deref().unwrap_or("its channel could not be written");
        MmusvError::Io {
            path: self.partial.display().to_string(),
            reason: format!("cannot write a message on {topic}: {earlier}"),
        }
    }

    /// Writes `topic`'s schema and channel; returns the channel's id.
    fn add_channel(&mut self, topic: &str, schema: &foxglove::Schema, message_encoding: &str) -> Result<u16> {
        let partial = self.partial.clone();
        let w = self.writer()?;
        let schema_id = w.add_schema(&schema.name, &schema.encoding, &schema.data).map_err(mcap_err(&partial))?;
        w.add_channel(schema_id, topic, message_encoding, &BTreeMap::new()).map_err(mcap_err(&partial))
    }

    /// Ends the holding of the first log time's messages (see the module's header): writes the schemas and
    /// channels they use, closes the chunk holding them, then writes the messages in the order they came.
    fn release(&mut self) -> Result<()> {
        if !matches!(self.hold, Hold::Holding { .. }) {
            return Ok(());
        }
        self.hold = Hold::Done;
        let partial = self.partial.clone();
        for (topic, schema, encoding) in std::mem::take(&mut self.pending) {
            let id = self.add_channel(&topic, &schema, &encoding)?;
            if let Some(slot) = self.channels.get_mut(&topic) {
                slot.id = Some(id);
            }
        }
        let flushed = self.writer()?.flush();
        flushed.map_err(|e| self.failed(&partial, &e))?;
        for h in std::mem::take(&mut self.held) {
            let Some(channel_id) = self.channels.get(&h.topic).and_then(|s| s.id) else {
                return Err(self.unwritten_channel(&h.topic));
            };
            let header =
                MessageHeader { channel_id, sequence: h.sequence, log_time: h.log_time, publish_time: h.log_time };
            let written = self.writer()?.write_to_known_channel(&header, &h.data);
            written.map_err(|e| self.failed(&partial, &e))?;
        }
        Ok(())
    }

    /// Checks that a message of schema `schema` may go to `topic`: a non-empty topic that carries no other
    /// schema yet.
    pub fn check_topic(&self, topic: &str, schema: &str) -> Result<()> {
        if topic.is_empty() {
            return Err(MmusvError::input("topic", "must not be empty (e.g. /usv0/lidar)"));
        }
        match self.channels.get(topic) {
            Some(slot) if slot.schema != schema => Err(MmusvError::input(
                "topic",
                format!("{topic} already carries {}, cannot write {schema} on it", slot.schema),
            )),
            _ => Ok(()),
        }
    }

    /// Writes an MCAP metadata record `name` holding `map` (e.g. scenario name, seed, mmusv version).
    pub fn metadata(&mut self, name: &str, map: &BTreeMap<String, String>) -> Result<()> {
        let partial = self.partial.clone();
        self.release()?;
        let record = Metadata { name: name.to_string(), metadata: map.clone() };
        let written = self.writer()?.write_metadata(&record);
        written.map_err(|e| self.failed(&partial, &e))
    }

    /// The error of a failed write: its reason, remembered if it is the first, else the first one's too.
    fn failed(&mut self, partial: &Path, e: &mcap::McapError) -> MmusvError {
        let reason = match &self.first_failure {
            Some(first) => format!("{} (after an earlier failure: {first})", mcap_reason(e)),
            None => {
                let r = mcap_reason(e);
                self.first_failure = Some(r.clone());
                r
            }
        };
        MmusvError::Io { path: partial.display().to_string(), reason }
    }

    /// Writes an attachment (e.g. the scenario YAML); `log_time_ns` is also used as its create time.
    pub fn attachment(&mut self, name: &str, media_type: &str, log_time_ns: u64, data: &[u8]) -> Result<()> {
        self.release()?;
        let partial = self.partial.clone();
        let a = Attachment {
            log_time: log_time_ns,
            create_time: log_time_ns,
            name: name.to_string(),
            media_type: media_type.to_string(),
            data: Cow::Borrowed(data),
        };
        let written = self.writer()?.attach(&a);
        written.map_err(|e| self.failed(&partial, &e))
    }

    /// Completes the file and renames it from `<path>.partial` to `path` (replacing `path` if it exists).
    pub fn finish(mut self) -> Result<RecordSummary> {
        if self.writer.is_some() {
            self.release()?;
        }
        let Some(writer) = self.writer.take() else {
            return Err(MmusvError::Io {
                path: self.partial.display().to_string(),
                reason: "the recording is already closed".into(),
            });
        };
        close(writer, &self.partial)?;
        std::fs::rename(&self.partial, &self.path).map_err(io_err(&self.path))?;
        let bytes = std::fs::metadata(&self.path).map_err(io_err(&self.path))?.len();
        Ok(RecordSummary {
            path: self.path.clone(),
            messages: self.messages,
            channels: self.channels.len() as u32,
            bytes,
        })
    }

    /// Completes the MCAP (valid, with everything written so far) but keeps it under `<path>.partial`, for a
    /// run that stopped early. Returns the `.partial` path.
    pub fn abandon(mut self) -> Result<PathBuf> {
        if self.writer.is_some() {
            self.release()?;
        }
        if let Some(writer) = self.writer.take() {
            close(writer, &self.partial)?;
        }
        Ok(self.partial.clone())
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        if self.writer.is_some() {
            let _ = self.release();
        }
        if let Some(writer) = self.writer.take() {
            let _ = close(writer, &self.partial);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_empty_path_is_refused_before_anything_is_written() {
        let e = Recorder::create(Path::new(""), true).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains("path") && e.contains("empty"), "{e}");
    }

    #[test]
    fn write_errors_name_the_operating_systems_reason() {
        let e = mcap::McapError::Io(std::io::Error::from_raw_os_error(28));
        let r = mcap_reason(&e);
        assert!(r.contains("No space left on device"), "{r}");
    }
}
