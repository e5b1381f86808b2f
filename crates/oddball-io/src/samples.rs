//! Samples read block by block, so a recording of hours is written without holding it: the
//! [`SampleBlocks`] a writer reads, and [`SampleSpill`], an append-only store of a session's
//! samples in an anonymous temporary file (the `tempfile` crate's; removed by the system when
//! closed, even after a crash).
//!
//! A live session takes eight channels at 500 Hz for hours: 115 MB an hour as f64. Kept in
//! memory, the session grows until the machine swaps; spilled, it costs a file handle and one
//! block of buffer, and the session's writers ([`crate::write_bci2000_blocks`],
//! [`crate::write_easy_blocks`]) read it back a block at a time. The values are stored as
//! little-endian f64, one sample's channels after another, so they come back bit for bit.

use std::fs::File;
use std::io::{self, BufWriter, Write};

use ndarray::{Array2, ArrayView2, ArrayViewMut2};

/// How many samples a writer reads at a time.
pub const BLOCK_SAMPLES: usize = 4096;

/// Samples `(n_channels, n_times)` in µV that can be read a block at a time.
pub trait SampleBlocks {
    fn n_channels(&self) -> usize;
    fn n_times(&self) -> usize;
    /// Fills `out`, `(n_channels, len)`, with the samples `[start, start + len)`.
    fn read_into(&self, start: usize, out: ArrayViewMut2<'_, f64>) -> io::Result<()>;
}

impl SampleBlocks for ArrayView2<'_, f64> {
    fn n_channels(&self) -> usize {
        self.nrows()
    }
    fn n_times(&self) -> usize {
        self.ncols()
    }
    fn read_into(&self, start: usize, mut out: ArrayViewMut2<'_, f64>) -> io::Result<()> {
        let len = out.ncols();
        if start + len > self.ncols() || out.nrows() != self.nrows() {
            return Err(out_of_range(start, len, self.ncols()));
        }
        out.assign(&self.slice(ndarray::s![.., start..start + len]));
        Ok(())
    }
}

fn out_of_range(start: usize, len: usize, n_times: usize) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidInput,
        format!("samples [{start}, {}) asked of {n_times}", start + len),
    )
}

/// Calls `each(start, block)` for consecutive blocks of at most [`BLOCK_SAMPLES`] samples.
pub fn for_each_block(
    samples: &dyn SampleBlocks,
    mut each: impl FnMut(usize, ArrayView2<'_, f64>) -> Result<(), crate::IoError>,
    read_err: impl Fn(io::Error) -> crate::IoError,
) -> Result<(), crate::IoError> {
    let (n_ch, n_times) = (samples.n_channels(), samples.n_times());
    let mut buf = Array2::zeros((n_ch, BLOCK_SAMPLES.min(n_times.max(1))));
    let mut start = 0;
    while start < n_times {
        let len = BLOCK_SAMPLES.min(n_times - start);
        let mut block = buf.slice_mut(ndarray::s![.., ..len]);
        samples
            .read_into(start, block.view_mut())
            .map_err(&read_err)?;
        each(start, block.view())?;
        start += len;
    }
    Ok(())
}

/// An append-only store of samples in an anonymous temporary file.
#[derive(Debug)]
pub struct SampleSpill {
    out: BufWriter<File>,
    n_channels: usize,
    n_times: usize,
    row: Vec<u8>,
}

impl SampleSpill {
    /// An empty store for `n_channels` channels, in the system's temporary directory.
    pub fn new(n_channels: usize) -> io::Result<Self> {
        Ok(Self {
            out: BufWriter::with_capacity(1 << 16, tempfile::tempfile()?),
            n_channels,
            n_times: 0,
            row: Vec::with_capacity(8 * n_channels),
        })
    }

    pub fn n_times(&self) -> usize {
        self.n_times
    }

    /// Appends `block`, `(n_channels, n)`.
    pub fn push(&mut self, block: ArrayView2<'_, f64>) -> io::Result<()> {
        if block.nrows() != self.n_channels {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "a block of {} channels for a store of {}",
                    block.nrows(),
                    self.n_channels
                ),
            ));
        }
        for col in block.columns() {
            self.row.clear();
            for x in col {
                self.row.extend_from_slice(&x.to_le_bytes());
            }
            self.out.write_all(&self.row)?;
        }
        self.n_times += block.ncols();
        Ok(())
    }

    /// The samples stored, readable by block.
    pub fn finish(self) -> io::Result<SpilledSamples> {
        let file = self.out.into_inner().map_err(|e| e.into_error())?;
        Ok(SpilledSamples {
            file,
            n_channels: self.n_channels,
            n_times: self.n_times,
        })
    }
}

/// The samples of a [`SampleSpill`], read back by block.
#[derive(Debug)]
pub struct SpilledSamples {
    file: File,
    n_channels: usize,
    n_times: usize,
}

impl SpilledSamples {
    /// All samples in memory, `(n_channels, n_times)`: for tests and short recordings.
    pub fn to_array(&self) -> io::Result<Array2<f64>> {
        let mut out = Array2::zeros((self.n_channels, self.n_times));
        self.read_into(0, out.view_mut())?;
        Ok(out)
    }
}

impl SampleBlocks for SpilledSamples {
    fn n_channels(&self) -> usize {
        self.n_channels
    }
    fn n_times(&self) -> usize {
        self.n_times
    }
    fn read_into(&self, start: usize, mut out: ArrayViewMut2<'_, f64>) -> io::Result<()> {
        let len = out.ncols();
        if start + len > self.n_times || out.nrows() != self.n_channels {
            return Err(out_of_range(start, len, self.n_times));
        }
        let width = 8 * self.n_channels;
        let mut bytes = vec![0u8; width * len];
        read_exact_at(&self.file, &mut bytes, (start * width) as u64)?;
        for (t, sample) in bytes.chunks_exact(width).enumerate() {
            for (c, x) in sample.chunks_exact(8).enumerate() {
                out[[c, t]] = f64::from_le_bytes(x.try_into().expect("8 bytes"));
            }
        }
        Ok(())
    }
}

#[cfg(unix)]
fn read_exact_at(file: &File, buf: &mut [u8], offset: u64) -> io::Result<()> {
    std::os::unix::fs::FileExt::read_exact_at(file, buf, offset)
}

#[cfg(not(unix))]
fn read_exact_at(file: &File, buf: &mut [u8], offset: u64) -> io::Result<()> {
    use std::io::{Read, Seek, SeekFrom};
    let mut f = file.try_clone()?;
    f.seek(SeekFrom::Start(offset))?;
    f.read_exact(buf)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spilled_samples_come_back_bit_for_bit_across_blocks() {
        let n = 2 * BLOCK_SAMPLES + 17;
        let x = Array2::from_shape_fn((3, n), |(c, t)| (c as f64 + 0.1) * (t as f64).sin() / 7.0);
        let mut spill = SampleSpill::new(3).unwrap();
        for start in (0..n).step_by(333) {
            let end = (start + 333).min(n);
            spill.push(x.slice(ndarray::s![.., start..end])).unwrap();
        }
        let back = spill.finish().unwrap();
        assert_eq!(back.n_times(), n);
        assert_eq!(back.to_array().unwrap(), x);
        let mut seen = 0;
        for_each_block(
            &back,
            |start, block| {
                assert_eq!(start, seen);
                assert_eq!(
                    block,
                    x.slice(ndarray::s![.., start..start + block.ncols()])
                );
                seen += block.ncols();
                Ok(())
            },
            |e| panic!("{e}"),
        )
        .unwrap();
        assert_eq!(seen, n);
        let mut small = Array2::zeros((3, 2));
        assert!(back.read_into(n - 1, small.view_mut()).is_err());
    }

    #[test]
    fn a_block_of_other_channels_is_refused() {
        let mut spill = SampleSpill::new(2).unwrap();
        assert!(spill.push(Array2::zeros((3, 4)).view()).is_err());
        assert_eq!(spill.n_times(), 0);
    }
}
