//! NIC TCP stream bytes through `NicDecoder`, fed in pieces of pseudo-random size.
//!
//! Input: byte 0 = flags (bit 0: ASCII mode, else binary; bit 1: trigger column; bit 2:
//! timestamp column; bit 3: an absurd channel count from a table instead of byte 1), byte 1 =
//! channel count, byte 2 = seed of the piece sizes, then the stream. Decoding in pieces must
//! give exactly what decoding the whole stream at once gives: the same samples, or the same
//! error at the same byte offset.
#![no_main]

use libfuzzer_sys::fuzz_target;
use oddball_io::nic::{NicDecoder, NicFormat, NicMode, NicSample};

const ABSURD_CHANNELS: [usize; 4] = [usize::MAX, usize::MAX / 4 + 1, 1 << 62, 1 << 30];

fn decode_all(format: NicFormat, pieces: &[&[u8]]) -> Result<Vec<NicSample>, String> {
    let mut d = NicDecoder::new(format);
    let mut out = Vec::new();
    for p in pieces {
        out.extend(d.push(p).map_err(|e| e.to_string())?);
        // Never more than one incomplete sample is held.
        let frame = format.n_channels.saturating_add(3).saturating_mul(4);
        assert!(d.pending() < frame.max(6 + 1024));
    }
    Ok(out)
}

fuzz_target!(|data: &[u8]| {
    if data.len() < 3 {
        return;
    }
    let (flags, n, seed, stream) = (data[0], data[1], data[2], &data[3..]);
    let n_channels = if flags & 8 != 0 {
        ABSURD_CHANNELS[n as usize % ABSURD_CHANNELS.len()]
    } else {
        n as usize
    };
    let format = NicFormat {
        mode: if flags & 1 != 0 {
            NicMode::Ascii
        } else {
            NicMode::Binary
        },
        n_channels,
        trigger: flags & 2 != 0,
        timestamp: flags & 4 != 0,
    };
    // Pieces of 0..=64 bytes from a xorshift generator.
    let mut state = u64::from(seed).wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut pieces = Vec::new();
    let mut rest = stream;
    while !rest.is_empty() {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let k = (state % 65) as usize;
        let (a, b) = rest.split_at(k.min(rest.len()));
        pieces.push(a);
        rest = b;
    }
    // An empty stream is still one (empty) push, as the whole is: the format is checked there.
    if pieces.is_empty() {
        pieces.push(stream);
    }
    let whole = decode_all(format, &[stream]);
    let cut = decode_all(format, &pieces);
    assert_eq!(whole, cut, "pieces decode differently from the whole stream");
});
