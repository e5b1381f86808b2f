//! Recording a live session as it runs: XDF (the Lab Streaming Layer's file format), four
//! streams on the session clock (seconds):
//!
//! * `EEG`: the raw samples as received, float32 µV, at the nominal rate;
//! * `Markers`: `cue C [calibration]`, `flash C target|nontarget` (at the onset the page drew),
//!   `decision C`, `abstain` ([`oddball_io::xdf::session_markers`]: each flash's code and flag,
//!   so the file trains and evaluates like any labelled recording);
//! * `Decisions`: each online decision as JSON (the session's `TrialRecord`);
//! * `Arm`: pen x, z (m) and joint angles θ1, θ2 (rad) after every block.
//!
//! Every block of samples ends with one `write_all` of all chunks since the last one (the
//! writer's `flush_block`), so a killed process leaves whole chunks on disk: the file opens in
//! oddball and in pyxdf and holds every sample up to the last flushed block.

use std::path::{Path, PathBuf};

use ndarray::{Array2, ArrayView2};
use oddball_io::xdf::{XdfFormat, XdfStream, XdfWriter};

use crate::LiveError;

/// The live session's XDF recorder. Dropped without [`Recorder::finish`] before any EEG sample
/// was written (a session that failed to start), it removes its file: no empty recordings.
#[derive(Debug)]
pub struct Recorder {
    /// `None` once finished.
    writer: Option<XdfWriter>,
    /// EEG samples written.
    n_times: u64,
    eeg: u32,
    markers: u32,
    decisions: u32,
    arm: u32,
    path: PathBuf,
}

impl Recorder {
    /// Creates `path` for a stream of `ch_names` at `sfreq` Hz.
    pub fn create(
        path: impl AsRef<Path>,
        ch_names: &[String],
        sfreq: f64,
        source_id: &str,
    ) -> Result<Self, LiveError> {
        let path = path.as_ref().to_path_buf();
        let mut writer = XdfWriter::create(&path)?;
        let mut eeg = XdfStream::eeg("oddball-eeg", ch_names.to_vec(), sfreq);
        eeg.source_id = source_id.to_string();
        let eeg = writer.add_stream(&eeg)?;
        let markers = writer.add_stream(&XdfStream::markers("oddball-markers"))?;
        let mut d = XdfStream::markers("oddball-decisions");
        d.stream_type = "oddball-decisions".into();
        d.channel_labels = vec!["decision".into()];
        let decisions = writer.add_stream(&d)?;
        let arm = writer.add_stream(&XdfStream {
            name: "oddball-arm".into(),
            stream_type: "Arm".into(),
            channel_labels: vec![
                "pen_x_m".into(),
                "pen_z_m".into(),
                "theta1_rad".into(),
                "theta2_rad".into(),
            ],
            unit: "SI".into(),
            nominal_srate: 0.0,
            format: XdfFormat::Double64,
            source_id: String::new(),
        })?;
        writer.flush_block()?;
        Ok(Self {
            writer: Some(writer),
            n_times: 0,
            eeg,
            markers,
            decisions,
            arm,
            path,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// EEG samples written so far.
    pub fn n_times(&self) -> u64 {
        self.n_times
    }

    /// A block of samples whose first is at `t0_ms`; ends the block (one write to disk).
    pub fn eeg(&mut self, t0_ms: f64, sfreq: f64, data: ArrayView2<f64>) -> Result<(), LiveError> {
        let ts: Vec<f64> = (0..data.ncols())
            .map(|i| t0_ms / 1e3 + i as f64 / sfreq)
            .collect();
        let eeg = self.eeg;
        let w = self.writer();
        w.push_numeric(eeg, &ts, data)?;
        w.flush_block()?;
        self.n_times += data.ncols() as u64;
        Ok(())
    }

    pub fn marker(&mut self, text: &str, ms: f64) -> Result<(), LiveError> {
        let markers = self.markers;
        Ok(self.writer().push_strings(markers, &[ms / 1e3], &[text])?)
    }

    pub fn decision(&mut self, json: &str, ms: f64) -> Result<(), LiveError> {
        let decisions = self.decisions;
        Ok(self
            .writer()
            .push_strings(decisions, &[ms / 1e3], &[json])?)
    }

    pub fn arm(&mut self, ms: f64, state: [f64; 4]) -> Result<(), LiveError> {
        let data = Array2::from_shape_vec((4, 1), state.to_vec()).expect("4 × 1");
        let arm = self.arm;
        Ok(self.writer().push_numeric(arm, &[ms / 1e3], data.view())?)
    }

    /// Writes the stream footers and closes the file.
    pub fn finish(mut self) -> Result<(), LiveError> {
        if let Some(w) = self.writer.take() {
            w.finish()?;
        }
        Ok(())
    }

    fn writer(&mut self) -> &mut XdfWriter {
        self.writer
            .as_mut()
            .expect("a recorder is written until finished")
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        if self.writer.take().is_some() && self.n_times == 0 {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}
