//! A recording played back as a live source, paced by the wall clock (BCI2000's FilePlayback):
//! `oddball online --source replay:FILE`.
//!
//! The session runs as it would live: its own schedule of flashes, its own cues and
//! decisions, its own recording. The EEG is the file's, sample by sample from its first, in µV.
//! A recording made by `oddball online` replays to the same flashes at the same samples when
//! the session is set up the same way (seed, commands, model or calibration): that is how a
//! session is re-run with another model, or a panel demonstrated without an amplifier.
//! [`PlaybackSource::coincidence`] says how many of this session's flashes fall on a flash of
//! the file; when few do, the EEG carries no response to this session's flashes and the
//! decisions mean nothing.
//!
//! At the end of the file the source stops with [`LiveError::RecordingEnded`]: the session
//! stops cleanly and its recording is kept.

use std::path::{Path, PathBuf};
use std::time::Instant;

use ndarray::{s, Array2};
use oddball_session::record::{calibration_part, CalibrationPart};
use oddball_signal::Event;

use crate::clock::Clock;
use crate::live::EegSource;
use crate::LiveError;

/// A recording as a live EEG source.
#[derive(Debug)]
pub struct PlaybackSource {
    path: PathBuf,
    data: Array2<f64>,
    sfreq: f64,
    ch_names: Vec<String>,
    events: Vec<Event>,
    calibration: Option<CalibrationPart>,
    clock: Clock,
    start_ms: f64,
    position: usize,
    paced: bool,
}

impl PlaybackSource {
    /// Reads `path` (any format `oddball_io::read` knows), paced by the wall clock.
    pub fn open(path: impl AsRef<Path>, clock: Clock) -> Result<Self, LiveError> {
        let path = path.as_ref();
        let rec = oddball_io::read(path)?;
        let calibration = calibration_part(&rec);
        let (data, sfreq, ch_names, events) = rec.raw.into_parts();
        if data.ncols() == 0 {
            return Err(LiveError::InvalidParameter {
                name: "replay",
                value: path.display().to_string(),
                reason: "the recording holds no samples".into(),
            });
        }
        Ok(Self {
            path: path.to_path_buf(),
            data,
            sfreq,
            ch_names,
            events: events.into_vec(),
            calibration,
            start_ms: clock.now_ms(),
            clock,
            position: 0,
            paced: true,
        })
    }

    /// The file resampled to `sfreq` Hz before it plays (polyphase, events moved with it:
    /// [`oddball_signal::resample::resample_raw`]), so a model at another rate can replay it.
    pub fn resampled(self, sfreq: f64) -> Result<Self, LiveError> {
        let raw = oddball_signal::Raw::new(
            self.data,
            self.sfreq,
            self.ch_names,
            oddball_signal::Events::new(self.events),
        )
        .and_then(|raw| oddball_signal::resample::resample_raw(&raw, sfreq))
        .map_err(oddball_session::SessionError::from)?;
        let (data, sfreq, ch_names, events) = raw.into_parts();
        // A recorded session's trial samples no longer hold at another rate.
        Ok(Self {
            data,
            sfreq,
            ch_names,
            events: events.into_vec(),
            calibration: None,
            ..self
        })
    }

    /// As fast as it can (tests).
    pub fn unpaced(mut self) -> Self {
        self.paced = false;
        self
    }

    /// Samples in the file.
    pub fn n_times(&self) -> usize {
        self.data.ncols()
    }

    /// The calibration a session recording begins with (see
    /// [`oddball_session::engine::Session::pass_calibration`]).
    pub fn calibration(&self) -> Option<CalibrationPart> {
        self.calibration
    }

    /// The file's events (flash markers become events of the flash's code).
    pub fn events(&self) -> &[Event] {
        &self.events
    }

    /// How many of `flashes` (onset sample, code) fall within `tolerance` samples of an event
    /// of the same code in the file.
    pub fn coincidence(&self, flashes: &[(u64, u32)], tolerance: u64) -> usize {
        let mut by_onset: Vec<(u64, u32)> = self
            .events
            .iter()
            .map(|e| (e.onset as u64, e.code))
            .collect();
        by_onset.sort_unstable();
        flashes
            .iter()
            .filter(|&&(onset, code)| {
                let lo = by_onset.partition_point(|&(o, _)| o + tolerance < onset);
                by_onset[lo..]
                    .iter()
                    .take_while(|&&(o, _)| o <= onset + tolerance)
                    .any(|&(_, c)| c == code)
            })
            .count()
    }
}

impl EegSource for PlaybackSource {
    fn sfreq(&self) -> f64 {
        self.sfreq
    }
    fn ch_names(&self) -> &[String] {
        &self.ch_names
    }
    fn wait(&mut self, n: usize) -> Result<(), LiveError> {
        if self.position + n > self.data.ncols() {
            return Err(LiveError::RecordingEnded {
                path: self.path.clone(),
                n_times: self.data.ncols(),
                seconds: self.data.ncols() as f64 / self.sfreq,
            });
        }
        if !self.paced {
            return Ok(());
        }
        let due = self.time_of((self.position + n) as u64);
        let at = self.clock.instant(due);
        let now = Instant::now();
        if at > now {
            std::thread::sleep(at - now);
        }
        Ok(())
    }
    fn take(&mut self, n: usize) -> Result<Array2<f64>, LiveError> {
        let end = self.position + n;
        if end > self.data.ncols() {
            return Err(LiveError::RecordingEnded {
                path: self.path.clone(),
                n_times: self.data.ncols(),
                seconds: self.data.ncols() as f64 / self.sfreq,
            });
        }
        let block = self.data.slice(s![.., self.position..end]).to_owned();
        self.position = end;
        Ok(block)
    }
    fn time_of(&self, sample: u64) -> f64 {
        self.start_ms + sample as f64 * 1e3 / self.sfreq
    }
    fn start_now(&mut self) {
        self.start_ms = self.clock.now_ms() - self.position as f64 * 1e3 / self.sfreq;
    }
}
