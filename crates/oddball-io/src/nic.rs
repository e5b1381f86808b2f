//! Neuroelectrics NIC's TCP data stream, the byte codec: the wire the paper reads its Starstim
//! through (the live TCP source is `oddball_live::nic`).
//!
//! NIC's data server (default port 1234) sends, per sample:
//! * **binary** mode: `n_channels` little-endian `i32` values in nV, then, if enabled, a
//!   little-endian `i32` trigger, then, if enabled, a little-endian `i64` Unix timestamp in ms;
//! * **ASCII** mode: a 6-byte length field (five digits and a tab, e.g. `00042\t`) followed by
//!   that many bytes of tab-separated values in the same order.
//!
//! [`NicDecoder`] turns bytes, cut anywhere, into samples and names the byte at fault in
//! garbage; [`encode`] writes them. No crate speaks NIC's protocol; it is written here from the
//! description in Neuroelectrics' NIC/MatNIC documentation.

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// A NIC stream that breaks the protocol, or a format that cannot be decoded.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum NicError {
    #[error("NIC stream, byte {offset}: {reason}")]
    Protocol { offset: u64, reason: String },
    #[error("invalid NIC format = {format}: {reason}")]
    InvalidFormat { format: String, reason: String },
}

/// Binary or ASCII framing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum NicMode {
    Binary,
    Ascii,
}

impl NicMode {
    /// `binary` or `ascii`.
    pub fn name(self) -> &'static str {
        match self {
            NicMode::Binary => "binary",
            NicMode::Ascii => "ascii",
        }
    }
}

/// What each sample carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct NicFormat {
    pub mode: NicMode,
    pub n_channels: usize,
    /// A trigger column after the channels.
    pub trigger: bool,
    /// A timestamp (ms) after the trigger.
    pub timestamp: bool,
}

impl NicFormat {
    /// Starstim 8 in binary mode with trigger and timestamp.
    pub fn starstim(mode: NicMode) -> Self {
        Self {
            mode,
            n_channels: 8,
            trigger: true,
            timestamp: true,
        }
    }

    /// Bytes per sample in binary mode.
    pub fn binary_len(&self) -> usize {
        4 * self.n_channels + 4 * usize::from(self.trigger) + 8 * usize::from(self.timestamp)
    }

    /// At least one value per sample and at most [`MAX_NIC_CHANNELS`] channels (an empty
    /// sample would decode forever from no bytes; a huge count would overflow the frame size).
    pub fn validate(&self) -> Result<(), NicError> {
        let bad = |reason: &str| {
            Err(NicError::InvalidFormat {
                format: format!(
                    "{} channels, trigger {}, timestamp {}",
                    self.n_channels, self.trigger, self.timestamp
                ),
                reason: reason.into(),
            })
        };
        if self.n_channels > MAX_NIC_CHANNELS {
            return bad(&format!("more than {MAX_NIC_CHANNELS} channels"));
        }
        if self.n_channels == 0 && !self.trigger && !self.timestamp {
            return bad("a sample of no values");
        }
        Ok(())
    }
}

/// Most channels a NIC stream may declare.
pub const MAX_NIC_CHANNELS: usize = 1024;

/// One sample off the wire.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NicSample {
    /// Channel values, nV.
    pub nv: Vec<i32>,
    pub trigger: Option<i32>,
    pub timestamp_ms: Option<i64>,
}

/// Largest ASCII payload accepted: 38 channels of 11 characters plus separators.
const MAX_ASCII_LEN: usize = 1024;

/// Appends one encoded sample to `out`.
pub fn encode(format: &NicFormat, s: &NicSample, out: &mut Vec<u8>) {
    match format.mode {
        NicMode::Binary => {
            for v in &s.nv {
                out.extend_from_slice(&v.to_le_bytes());
            }
            if format.trigger {
                out.extend_from_slice(&s.trigger.unwrap_or(0).to_le_bytes());
            }
            if format.timestamp {
                out.extend_from_slice(&s.timestamp_ms.unwrap_or(0).to_le_bytes());
            }
        }
        NicMode::Ascii => {
            let mut fields: Vec<String> = s.nv.iter().map(|v| v.to_string()).collect();
            if format.trigger {
                fields.push(s.trigger.unwrap_or(0).to_string());
            }
            if format.timestamp {
                fields.push(s.timestamp_ms.unwrap_or(0).to_string());
            }
            let body = fields.join("\t");
            out.extend_from_slice(format!("{:05}\t", body.len()).as_bytes());
            out.extend_from_slice(body.as_bytes());
        }
    }
}

/// Incremental decoder: feed bytes as they arrive, get whole samples.
#[derive(Debug, Clone)]
pub struct NicDecoder {
    format: NicFormat,
    buf: Vec<u8>,
    /// Bytes consumed so far (for error offsets).
    consumed: u64,
}

impl NicDecoder {
    pub fn new(format: NicFormat) -> Self {
        Self {
            format,
            buf: Vec::new(),
            consumed: 0,
        }
    }

    /// Bytes received but not yet a whole sample.
    pub fn pending(&self) -> usize {
        self.buf.len()
    }

    /// Forgets a partial sample (after a reconnect).
    pub fn reset(&mut self) {
        self.consumed += self.buf.len() as u64;
        self.buf.clear();
    }

    /// Decodes every whole sample in `bytes` (plus what was pending).
    pub fn push(&mut self, bytes: &[u8]) -> Result<Vec<NicSample>, NicError> {
        self.format.validate()?;
        self.buf.extend_from_slice(bytes);
        let mut out = Vec::new();
        let mut at = 0;
        let f = self.format;
        loop {
            match f.mode {
                NicMode::Binary => {
                    let len = f.binary_len();
                    if self.buf.len() - at < len {
                        break;
                    }
                    let b = &self.buf[at..at + len];
                    let i32_at = |k: usize| {
                        i32::from_le_bytes(b[4 * k..4 * k + 4].try_into().expect("4 bytes"))
                    };
                    let nv = (0..f.n_channels).map(i32_at).collect();
                    let trigger = f.trigger.then(|| i32_at(f.n_channels));
                    let ts_at = 4 * f.n_channels + 4 * usize::from(f.trigger);
                    let timestamp_ms = f.timestamp.then(|| {
                        i64::from_le_bytes(b[ts_at..ts_at + 8].try_into().expect("8 bytes"))
                    });
                    out.push(NicSample {
                        nv,
                        trigger,
                        timestamp_ms,
                    });
                    at += len;
                }
                NicMode::Ascii => {
                    if self.buf.len() - at < 6 {
                        break;
                    }
                    let head = &self.buf[at..at + 6];
                    let offset = self.consumed + at as u64;
                    let len = parse_length(head).ok_or_else(|| NicError::Protocol {
                        offset,
                        reason: format!(
                            "length field {:?} is not five digits and a tab",
                            String::from_utf8_lossy(head)
                        ),
                    })?;
                    if len > MAX_ASCII_LEN {
                        return Err(NicError::Protocol {
                            offset,
                            reason: format!("length {len} exceeds {MAX_ASCII_LEN} bytes"),
                        });
                    }
                    if self.buf.len() - at < 6 + len {
                        break;
                    }
                    let body = &self.buf[at + 6..at + 6 + len];
                    out.push(parse_ascii(&f, body, offset + 6)?);
                    at += 6 + len;
                }
            }
        }
        self.buf.drain(..at);
        self.consumed += at as u64;
        Ok(out)
    }
}

fn parse_length(head: &[u8]) -> Option<usize> {
    if head.len() != 6 || head[5] != b'\t' || !head[..5].iter().all(u8::is_ascii_digit) {
        return None;
    }
    std::str::from_utf8(&head[..5]).ok()?.parse().ok()
}

fn parse_ascii(f: &NicFormat, body: &[u8], offset: u64) -> Result<NicSample, NicError> {
    let text = std::str::from_utf8(body).map_err(|e| NicError::Protocol {
        offset: offset + e.valid_up_to() as u64,
        reason: "a sample is not UTF-8 text".into(),
    })?;
    let fields: Vec<&str> = text.split('\t').collect();
    let want = f.n_channels + usize::from(f.trigger) + usize::from(f.timestamp);
    if fields.len() != want {
        return Err(NicError::Protocol {
            offset,
            reason: format!("{} values in a sample, expected {want}", fields.len()),
        });
    }
    let mut pos = offset;
    let mut ints = Vec::with_capacity(want);
    for v in &fields {
        let n: i64 = v.trim().parse().map_err(|_| NicError::Protocol {
            offset: pos,
            reason: format!("value {v:?} is not an integer"),
        })?;
        ints.push(n);
        pos += v.len() as u64 + 1;
    }
    let to_i32 = |k: usize| {
        i32::try_from(ints[k]).map_err(|_| NicError::Protocol {
            offset,
            reason: format!("value {} does not fit 32 bits", ints[k]),
        })
    };
    Ok(NicSample {
        nv: (0..f.n_channels).map(to_i32).collect::<Result<_, _>>()?,
        trigger: if f.trigger {
            Some(to_i32(f.n_channels)?)
        } else {
            None
        },
        timestamp_ms: f.timestamp.then(|| ints[want - 1]),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn sample(k: i32, f: &NicFormat) -> NicSample {
        NicSample {
            nv: (0..f.n_channels as i32)
                .map(|c| k * 1000 - c * 7 + i32::MIN / 3)
                .collect(),
            trigger: f.trigger.then_some(k % 5),
            timestamp_ms: f.timestamp.then_some(1_700_000_000_000 + 2 * i64::from(k)),
        }
    }

    proptest! {
        /// Any cut of the byte stream decodes to the samples sent, in both modes.
        #[test]
        fn decoding_survives_any_cuts(
            cuts in proptest::collection::vec(1usize..200, 1..30),
            ascii in any::<bool>(),
            trigger in any::<bool>(),
            timestamp in any::<bool>(),
        ) {
            let f = NicFormat { mode: if ascii { NicMode::Ascii } else { NicMode::Binary }, n_channels: 8, trigger, timestamp };
            let sent: Vec<NicSample> = (0..40).map(|k| sample(k, &f)).collect();
            let mut bytes = Vec::new();
            for s in &sent { encode(&f, s, &mut bytes); }
            let mut d = NicDecoder::new(f);
            let mut got = Vec::new();
            let mut at = 0;
            for c in cuts.iter().cycle() {
                if at >= bytes.len() { break; }
                let end = (at + c).min(bytes.len());
                got.extend(d.push(&bytes[at..end]).unwrap());
                at = end;
            }
            prop_assert_eq!(got, sent);
            prop_assert_eq!(d.pending(), 0);
        }
    }

    #[test]
    fn ascii_framing_is_five_digits_and_a_tab() {
        let f = NicFormat {
            mode: NicMode::Ascii,
            n_channels: 2,
            trigger: true,
            timestamp: false,
        };
        let mut b = Vec::new();
        encode(
            &f,
            &NicSample {
                nv: vec![-12, 345],
                trigger: Some(7),
                timestamp_ms: None,
            },
            &mut b,
        );
        assert_eq!(b, b"00009\t-12\t345\t7");
    }

    #[test]
    fn garbage_is_an_error_naming_the_byte() {
        let f = NicFormat {
            mode: NicMode::Ascii,
            n_channels: 2,
            trigger: false,
            timestamp: false,
        };
        let mut d = NicDecoder::new(f);
        assert_eq!(d.push(b"00003\t1\t2").unwrap().len(), 1);
        let err = d.push(b"0x003\t1\t2").unwrap_err();
        assert!(matches!(err, NicError::Protocol { offset: 9, .. }), "{err}");
        let mut d = NicDecoder::new(f);
        let err = d.push(b"99999\t").unwrap_err();
        assert!(err.to_string().contains("exceeds"), "{err}");
        let mut d = NicDecoder::new(f);
        let err = d.push(b"00004\t1\tzz").unwrap_err();
        assert!(matches!(err, NicError::Protocol { offset: 8, .. }), "{err}");
        let mut d = NicDecoder::new(f);
        let err = d.push(b"00005\t1\t2\t3").unwrap_err();
        assert!(err.to_string().contains("3 values"), "{err}");
    }

    /// Found by the `nic` fuzz target: a format of no values decoded empty samples from no bytes
    /// forever (out of memory), and a huge channel count overflowed the frame size. Both are now
    /// refused with an error naming the format, for any input.
    #[test]
    fn fuzz_regression_formats_of_no_values_or_absurd_channel_counts_are_refused() {
        let crash = [0x30u8, 0x30, 0x30, 0x30, 0x33, 0x09, 0x31];
        for (mode, n, trigger, timestamp) in [
            (NicMode::Binary, 0, false, false),
            (NicMode::Ascii, 0, false, false),
            (NicMode::Binary, usize::MAX, true, true),
            (NicMode::Binary, 1 << 62, false, false),
            (NicMode::Ascii, 1 << 30, false, false),
        ] {
            let format = NicFormat {
                mode,
                n_channels: n,
                trigger,
                timestamp,
            };
            let err = NicDecoder::new(format).push(&crash).unwrap_err();
            assert!(err.to_string().contains("NIC format"), "{err}");
        }
        // A trigger-only stream is a valid (if odd) format.
        let format = NicFormat {
            mode: NicMode::Binary,
            n_channels: 0,
            trigger: true,
            timestamp: false,
        };
        assert_eq!(
            NicDecoder::new(format).push(&[1, 0, 0, 0]).unwrap().len(),
            1
        );
    }
}
