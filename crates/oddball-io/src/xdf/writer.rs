//! Writing XDF: the live [`XdfWriter`] and the offline [`write_xdf`].

use std::fmt::Write as _;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

use ndarray::ArrayView2;
use oddball_signal::Raw;

use crate::edf::event_annotation_text;
use crate::writing::{check_not_empty, check_writable, TempFile};
use crate::IoError;

use super::chunk::*;
use super::types::*;
use super::xml::*;

// ---------------------------------------------------------------------------------------------
// The live writer
// ---------------------------------------------------------------------------------------------

#[derive(Debug)]
pub(super) struct WriterStream {
    id: u32,
    spec: XdfStream,
    header_written: bool,
    /// Sample bytes (timestamp byte, timestamp, values) since the last flush.
    pending: Vec<u8>,
    pending_n: u64,
    /// ClockOffset pairs since the last flush.
    pending_clock: Vec<(f64, f64)>,
    clock_offsets: Vec<(f64, f64)>,
    first_timestamp: Option<f64>,
    last_timestamp: Option<f64>,
    sample_count: u64,
}

/// Writes an XDF file as a session runs (see the module documentation).
#[derive(Debug)]
pub struct XdfWriter {
    path: PathBuf,
    /// `None` once finished.
    file: Option<File>,
    streams: Vec<WriterStream>,
    bytes_written: u64,
    /// A write failed: the file may end in a partial chunk, so nothing more is appended.
    failed: bool,
    last_boundary: Option<f64>,
    max_timestamp: Option<f64>,
}

impl XdfWriter {
    /// Creates the file (refusing to replace an existing one: a recorder must not destroy an
    /// earlier session) and writes the magic code and the FileHeader chunk at once.
    pub fn create(path: impl AsRef<Path>) -> Result<XdfWriter, IoError> {
        let path = path.as_ref();
        let file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(path)
            .map_err(|source| IoError::Io {
                path: path.to_path_buf(),
                action: "create",
                source,
            })?;
        Self::start(file, path.to_path_buf())
    }

    fn start(file: File, path: PathBuf) -> Result<XdfWriter, IoError> {
        let mut w = XdfWriter {
            path,
            file: Some(file),
            streams: Vec::new(),
            bytes_written: 0,
            failed: false,
            last_boundary: None,
            max_timestamp: None,
        };
        let mut block = MAGIC.to_vec();
        let xml = format!(
            "<?xml version=\"1.0\"?>\n<info><version>1.0</version><writer>oddball-io {}</writer></info>\n",
            env!("CARGO_PKG_VERSION")
        );
        put_chunk(&mut block, TAG_FILE_HEADER, &[xml.as_bytes()]);
        w.write_block(&block)?;
        Ok(w)
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Bytes handed to the operating system so far (the file's size).
    pub fn bytes_written(&self) -> u64 {
        self.bytes_written
    }

    /// Bytes of samples buffered since the last flush.
    pub fn pending_bytes(&self) -> usize {
        self.streams.iter().map(|s| s.pending.len()).sum()
    }

    /// Samples written so far (buffered ones included) to stream `id`.
    pub fn sample_count(&self, id: u32) -> Option<u64> {
        self.streams
            .iter()
            .find(|s| s.id == id)
            .map(|s| s.sample_count)
    }

    fn unsupported(&self, what: String) -> IoError {
        IoError::Unsupported {
            path: self.path.clone(),
            what,
        }
    }

    fn check_usable(&self) -> Result<(), IoError> {
        if self.failed {
            return Err(self.unsupported(
                "writing to an XDF file after a failed write (it may end in a partial chunk)"
                    .into(),
            ));
        }
        Ok(())
    }

    /// Adds a stream and returns its id (1, 2, …). Its StreamHeader is written at the next
    /// flush. Refused: no channel or more than [`MAX_CHANNELS`], a string stream with more than
    /// one channel, a negative or non-finite rate, text with control characters.
    pub fn add_stream(&mut self, stream: &XdfStream) -> Result<u32, IoError> {
        self.check_usable()?;
        let n = stream.channel_labels.len();
        if n == 0 || n > MAX_CHANNELS {
            return Err(self.unsupported(format!(
                "stream {:?} with {n} channels (1 to {MAX_CHANNELS})",
                stream.name
            )));
        }
        if stream.format == XdfFormat::String && n != 1 {
            return Err(self.unsupported(format!(
                "string stream {:?} with {n} channels (this writer writes one-channel string streams)",
                stream.name
            )));
        }
        if !(stream.nominal_srate.is_finite() && stream.nominal_srate >= 0.0) {
            return Err(self.unsupported(format!(
                "stream {:?} with nominal_srate {} (finite and >= 0; 0 = irregular)",
                stream.name, stream.nominal_srate
            )));
        }
        let texts = [
            ("name", &stream.name),
            ("type", &stream.stream_type),
            ("unit", &stream.unit),
            ("source_id", &stream.source_id),
        ];
        for (what, text) in texts
            .into_iter()
            .chain(stream.channel_labels.iter().map(|l| ("channel label", l)))
        {
            if let Some(p) = xml_text_problem(text) {
                return Err(self.unsupported(format!("stream {what} {text:?} {p}")));
            }
        }
        let id = self.streams.len() as u32 + 1;
        self.streams.push(WriterStream {
            id,
            spec: stream.clone(),
            header_written: false,
            pending: Vec::new(),
            pending_n: 0,
            pending_clock: Vec::new(),
            clock_offsets: Vec::new(),
            first_timestamp: None,
            last_timestamp: None,
            sample_count: 0,
        });
        Ok(id)
    }

    fn stream_index(&self, id: u32) -> Result<usize, IoError> {
        self.streams
            .iter()
            .position(|s| s.id == id)
            .ok_or_else(|| IoError::Missing {
                path: self.path.clone(),
                what: "XDF stream id",
                name: id.to_string(),
                available: self.streams.iter().map(|s| s.id.to_string()).collect(),
            })
    }

    fn check_timestamps(&self, k: usize, timestamps: &[f64], n: usize) -> Result<(), IoError> {
        let s = &self.streams[k];
        if timestamps.len() != n {
            return Err(self.unsupported(format!(
                "stream {} ({:?}): {} timestamps for {n} samples",
                s.id,
                s.spec.name,
                timestamps.len()
            )));
        }
        if let Some(i) = timestamps.iter().position(|t| !t.is_finite()) {
            return Err(self.unsupported(format!(
                "stream {} ({:?}): timestamp {i} is {} (timestamps must be finite)",
                s.id, s.spec.name, timestamps[i]
            )));
        }
        Ok(())
    }

    fn note_timestamps(&mut self, k: usize, timestamps: &[f64]) {
        let (Some(&first), Some(&last)) = (timestamps.first(), timestamps.last()) else {
            return;
        };
        let max = timestamps.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let s = &mut self.streams[k];
        s.first_timestamp.get_or_insert(first);
        s.last_timestamp = Some(last);
        s.sample_count += timestamps.len() as u64;
        s.pending_n += timestamps.len() as u64;
        self.max_timestamp = Some(self.max_timestamp.map_or(max, |m| m.max(max)));
        self.last_boundary.get_or_insert(first);
    }

    /// Buffers samples of numeric stream `id`: `data` is `(n_channels, n_samples)`, one
    /// timestamp (seconds) per sample. Nothing is buffered when any check fails.
    pub fn push_numeric(
        &mut self,
        id: u32,
        timestamps: &[f64],
        data: ArrayView2<'_, f64>,
    ) -> Result<(), IoError> {
        self.check_usable()?;
        let k = self.stream_index(id)?;
        let s = &self.streams[k];
        let format = s.spec.format;
        if !format.is_numeric() {
            return Err(self.unsupported(format!(
                "push_numeric to string stream {id} ({:?}); use push_strings",
                s.spec.name
            )));
        }
        let n_ch = s.spec.channel_labels.len();
        if data.nrows() != n_ch {
            return Err(self.unsupported(format!(
                "stream {id} ({:?}) has {n_ch} channels, but the data has {} rows",
                s.spec.name,
                data.nrows()
            )));
        }
        self.check_timestamps(k, timestamps, data.ncols())?;
        let s = &mut self.streams[k];
        let start = s.pending.len();
        let vb = format.value_bytes().unwrap_or(8);
        s.pending.reserve(timestamps.len() * (9 + n_ch * vb));
        for (t, (&ts, col)) in timestamps.iter().zip(data.columns()).enumerate() {
            s.pending.push(8);
            s.pending.extend_from_slice(&ts.to_le_bytes());
            for (c, &x) in col.iter().enumerate() {
                if let Err(reason) = put_value(&mut s.pending, format, x) {
                    s.pending.truncate(start);
                    return Err(IoError::UnwritableSample {
                        path: self.path.clone(),
                        channel: s.spec.channel_labels[c].clone(),
                        channel_index: c,
                        sample: t,
                        value: x,
                        reason,
                    });
                }
            }
        }
        self.note_timestamps(k, timestamps);
        Ok(())
    }

    /// Buffers samples of a (one-channel) string stream `id`: one text per timestamp.
    pub fn push_strings(
        &mut self,
        id: u32,
        timestamps: &[f64],
        values: &[&str],
    ) -> Result<(), IoError> {
        self.check_usable()?;
        let k = self.stream_index(id)?;
        let s = &self.streams[k];
        if s.spec.format != XdfFormat::String {
            return Err(self.unsupported(format!(
                "push_strings to {} stream {id} ({:?}); use push_numeric",
                s.spec.format.name(),
                s.spec.name
            )));
        }
        self.check_timestamps(k, timestamps, values.len())?;
        let s = &mut self.streams[k];
        for (&ts, v) in timestamps.iter().zip(values) {
            s.pending.push(8);
            s.pending.extend_from_slice(&ts.to_le_bytes());
            put_varlen(&mut s.pending, v.len() as u64);
            s.pending.extend_from_slice(v.as_bytes());
        }
        self.note_timestamps(k, timestamps);
        Ok(())
    }

    /// Buffers a ClockOffset chunk for stream `id`: at `collection_time` (the recorder's clock)
    /// the stream's clock was `offset` seconds behind (both finite).
    pub fn push_clock_offset(
        &mut self,
        id: u32,
        collection_time: f64,
        offset: f64,
    ) -> Result<(), IoError> {
        self.check_usable()?;
        let k = self.stream_index(id)?;
        if !(collection_time.is_finite() && offset.is_finite()) {
            return Err(self.unsupported(format!(
                "stream {id}: clock offset {offset} at {collection_time} (both must be finite)"
            )));
        }
        self.streams[k]
            .pending_clock
            .push((collection_time, offset));
        Ok(())
    }

    /// Everything buffered, as whole chunks; with `footers`, a StreamFooter per stream after it.
    fn take_block(&mut self, footers: bool) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.pending_bytes() + 64 * self.streams.len());
        for s in &mut self.streams {
            if !s.header_written {
                let xml = stream_header_xml(&s.spec, s.first_timestamp);
                put_chunk(
                    &mut out,
                    TAG_STREAM_HEADER,
                    &[&s.id.to_le_bytes(), xml.as_bytes()],
                );
                s.header_written = true;
            }
        }
        for s in &mut self.streams {
            if s.pending_n > 0 {
                let mut head = s.id.to_le_bytes().to_vec();
                put_varlen(&mut head, s.pending_n);
                put_chunk(&mut out, TAG_SAMPLES, &[&head, &s.pending]);
                s.pending.clear();
                s.pending_n = 0;
            }
        }
        for s in &mut self.streams {
            for (t, v) in s.pending_clock.drain(..) {
                put_chunk(
                    &mut out,
                    TAG_CLOCK_OFFSET,
                    &[&s.id.to_le_bytes(), &t.to_le_bytes(), &v.to_le_bytes()],
                );
                s.clock_offsets.push((t, v));
            }
        }
        if let (Some(max), Some(last)) = (self.max_timestamp, self.last_boundary) {
            if max - last >= BOUNDARY_INTERVAL_S {
                put_chunk(&mut out, TAG_BOUNDARY, &[&BOUNDARY_UUID]);
                self.last_boundary = Some(max);
            }
        }
        if footers {
            for s in &self.streams {
                let mut x = String::from("<?xml version=\"1.0\"?>\n<info>");
                if let (Some(f), Some(l)) = (s.first_timestamp, s.last_timestamp) {
                    let _ = write!(
                        x,
                        "<first_timestamp>{f}</first_timestamp><last_timestamp>{l}</last_timestamp>"
                    );
                }
                let _ = write!(x, "<sample_count>{}</sample_count>", s.sample_count);
                x.push_str("<clock_offsets>");
                for (t, v) in &s.clock_offsets {
                    let _ = write!(x, "<offset><time>{t}</time><value>{v}</value></offset>");
                }
                x.push_str("</clock_offsets></info>\n");
                put_chunk(
                    &mut out,
                    TAG_STREAM_FOOTER,
                    &[&s.id.to_le_bytes(), x.as_bytes()],
                );
            }
        }
        out
    }

    fn write_block(&mut self, block: &[u8]) -> Result<usize, IoError> {
        if block.is_empty() {
            return Ok(0);
        }
        let Some(file) = self.file.as_mut() else {
            return Err(self.unsupported("writing to a finished XDF file".into()));
        };
        if let Err(source) = file.write_all(block).and_then(|()| file.flush()) {
            self.failed = true;
            return Err(IoError::Io {
                path: self.path.clone(),
                action: "write",
                source,
            });
        }
        self.bytes_written += block.len() as u64;
        Ok(block.len())
    }

    /// Writes every chunk buffered since the last flush with one `write_all`, then `flush`.
    /// Returns the bytes written (0 when nothing was buffered).
    pub fn flush_block(&mut self) -> Result<usize, IoError> {
        self.check_usable()?;
        let block = self.take_block(false);
        self.write_block(&block)
    }

    /// Asks the operating system to put the written bytes on the disk (`fsync`).
    pub fn sync(&mut self) -> Result<(), IoError> {
        if let Some(f) = self.file.as_mut() {
            crate::writing::sync(f).map_err(|source| IoError::Io {
                path: self.path.clone(),
                action: "write",
                source,
            })?;
        }
        Ok(())
    }

    /// Flushes, writes a StreamFooter per stream (first and last timestamp, sample count, clock
    /// offsets), syncs and closes the file. Returns the file size in bytes.
    pub fn finish(mut self) -> Result<u64, IoError> {
        self.check_usable()?;
        let block = self.take_block(true);
        self.write_block(&block)?;
        self.sync()?;
        self.file = None;
        Ok(self.bytes_written)
    }
}

impl Drop for XdfWriter {
    fn drop(&mut self) {
        if self.file.is_some() && !self.failed {
            let _ = self.flush_block();
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The offline writer
// ---------------------------------------------------------------------------------------------

/// Options of [`write_xdf`].
#[derive(Debug, Clone, PartialEq)]
pub struct XdfWriteOptions {
    /// The EEG stream's name; default `oddball EEG`.
    pub stream_name: String,
    /// Default `""`.
    pub source_id: String,
    /// Default [`XdfFormat::Double64`] (bit-exact); [`XdfFormat::Float32`] halves the size.
    pub format: XdfFormat,
    /// Timestamp of the first sample in seconds; sample `i` is at `start_time + i / sfreq`.
    pub start_time: f64,
    /// Write the events as a string stream `oddball markers` (type `Markers`); default true.
    pub markers: bool,
    /// Samples per Samples chunk; default 500.
    pub samples_per_chunk: usize,
}

impl Default for XdfWriteOptions {
    fn default() -> Self {
        Self {
            stream_name: "oddball EEG".into(),
            source_id: String::new(),
            format: XdfFormat::Double64,
            start_time: 0.0,
            markers: true,
            samples_per_chunk: 500,
        }
    }
}

/// What [`write_xdf`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct XdfWriteSummary {
    pub n_samples: usize,
    pub n_channels: usize,
    pub n_markers: usize,
    pub bytes: u64,
    /// The largest `|stored − x|` over all samples, in µV (0 for double64).
    pub max_rounding_uv: f64,
}

/// The timestamp [`write_xdf`] gives sample `i`: `start_time + i / sfreq`.
pub fn sample_timestamp(start_time: f64, i: usize, sfreq: f64) -> f64 {
    start_time + i as f64 / sfreq
}

/// Writes `raw` as an XDF file: one EEG stream (unit microvolts, each sample with its
/// timestamp) and, with [`XdfWriteOptions::markers`], the events as a string stream (each as
/// [`event_annotation_text`] at its onset's timestamp), then footers. The file is written to
/// a temporary file beside `path` and renamed into place. Refused before anything is written:
/// an empty recording, a string format, a non-finite start time, a sample that does not fit the
/// format ([`IoError::UnwritableSample`]), names with control characters.
pub fn write_xdf(
    path: impl AsRef<Path>,
    raw: &Raw,
    options: &XdfWriteOptions,
) -> Result<XdfWriteSummary, IoError> {
    let path = path.as_ref();
    let unsupported = |what: String| IoError::Unsupported {
        path: path.to_path_buf(),
        what,
    };
    check_not_empty(path, raw, "XDF")?;
    if !options.format.is_numeric() {
        return Err(unsupported("an EEG stream in string format".into()));
    }
    if !options.start_time.is_finite() {
        return Err(unsupported(format!(
            "start time {} (must be finite)",
            options.start_time
        )));
    }
    let format = options.format;
    let max_rounding = check_writable(
        path,
        raw,
        "beyond the range of the stream's number type",
        |x| {
            let mut b = Vec::with_capacity(8);
            put_value(&mut b, format, x).ok()?;
            Some(match format {
                XdfFormat::Float32 => f64::from(x as f32),
                XdfFormat::Double64 => x,
                _ => x.round(),
            })
        },
    )?;
    let sfreq = raw.sfreq();
    let n_times = raw.n_times();
    let eeg = XdfStream {
        name: options.stream_name.clone(),
        stream_type: "EEG".into(),
        channel_labels: raw.ch_names().to_vec(),
        unit: "microvolts".into(),
        nominal_srate: sfreq,
        format,
        source_id: options.source_id.clone(),
    };

    let (tmp, file) = TempFile::create(path)?;
    let mut w = XdfWriter::start(file, tmp.path.clone())?;
    let eeg_id = w.add_stream(&eeg)?;
    let marker_id = if options.markers {
        Some(w.add_stream(&XdfStream::markers("oddball markers"))?)
    } else {
        None
    };
    let events = raw.events().as_slice();
    let mut next_event = 0;
    let step = options.samples_per_chunk.max(1);
    let mut start = 0;
    while start < n_times {
        let end = (start + step).min(n_times);
        let ts: Vec<f64> = (start..end)
            .map(|i| sample_timestamp(options.start_time, i, sfreq))
            .collect();
        w.push_numeric(eeg_id, &ts, raw.data().slice(ndarray::s![.., start..end]))?;
        if let Some(mid) = marker_id {
            let mut mts = Vec::new();
            let mut texts = Vec::new();
            while next_event < events.len() && events[next_event].onset < end {
                let e = &events[next_event];
                mts.push(sample_timestamp(options.start_time, e.onset, sfreq));
                texts.push(event_annotation_text(e));
                next_event += 1;
            }
            let refs: Vec<&str> = texts.iter().map(String::as_str).collect();
            w.push_strings(mid, &mts, &refs)?;
        }
        w.flush_block()?;
        start = end;
    }
    let bytes = w.finish()?;
    tmp.persist(path)?;
    Ok(XdfWriteSummary {
        n_samples: n_times,
        n_channels: raw.n_channels(),
        n_markers: if options.markers { events.len() } else { 0 },
        bytes,
        max_rounding_uv: max_rounding,
    })
}
