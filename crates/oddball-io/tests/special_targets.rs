//! Outputs aimed at a device or a pipe (`-o /dev/null`, a named pipe read by another program)
//! are written in place: a temporary file renamed over `/dev/null` would have replaced the
//! device with a regular file (as root it did, and every later program that read `/dev/null` got
//! what earlier ones had written there).
#![cfg(unix)]

use std::io::Read;
use std::os::unix::fs::FileTypeExt;
use std::path::Path;

use ndarray::Array2;
use oddball_io::{write_atomic, write_bci2000, write_edf_plus, write_xdf, AtomicFile};
use oddball_signal::{Events, Raw};

fn assert_dev_null_is_device() {
    let meta = std::fs::metadata("/dev/null").unwrap();
    assert!(
        meta.file_type().is_char_device(),
        "/dev/null is no longer a character device: {:?}",
        meta.file_type()
    );
}

fn raw() -> Raw {
    let data = Array2::from_shape_fn((2, 500), |(c, t)| (c as f64 + 1.0) * (t as f64 * 0.1).sin());
    Raw::new(
        data,
        250.0,
        vec!["Cz".into(), "Pz".into()],
        Events::default(),
    )
    .unwrap()
}

#[test]
fn writing_to_dev_null_leaves_the_device_in_place() {
    write_atomic("/dev/null", b"model bytes").unwrap();
    assert_dev_null_is_device();
    let mut f = AtomicFile::create("/dev/null").unwrap();
    std::io::Write::write_all(&mut f, b"more").unwrap();
    f.commit().unwrap();
    assert_dev_null_is_device();
    // Reading /dev/null still gives nothing (a regular file would give what was written).
    let mut back = Vec::new();
    std::fs::File::open("/dev/null")
        .unwrap()
        .read_to_end(&mut back)
        .unwrap();
    assert!(back.is_empty(), "read {} bytes from /dev/null", back.len());
}

#[test]
fn recordings_written_to_dev_null_leave_the_device_in_place() {
    let raw = raw();
    write_xdf("/dev/null", &raw, &Default::default()).unwrap();
    assert_dev_null_is_device();
    write_edf_plus("/dev/null", &raw).unwrap();
    assert_dev_null_is_device();
    write_bci2000("/dev/null", &raw, &[], &Default::default()).unwrap();
    assert_dev_null_is_device();
}

#[test]
fn a_named_pipe_receives_the_bytes_and_stays_a_pipe() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("out.fifo");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(made.success());
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read(fifo).unwrap())
    };
    write_atomic(&fifo, b"through the pipe").unwrap();
    assert_eq!(reader.join().unwrap(), b"through the pipe");
    let kind = std::fs::metadata(&fifo).unwrap().file_type();
    assert!(kind.is_fifo(), "{:?}", kind);
    // No temporary file was left beside it.
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(left.len(), 1);
    assert!(Path::new(&fifo).exists());
}
