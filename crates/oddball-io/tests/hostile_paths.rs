//! Issue #30: inputs that would cost the machine without end are refused before they do — a MAT
//! zip bomb (a small file whose compressed variable inflates to hundreds of MB), and paths that
//! are devices, pipes or links to them (`/dev/zero` as a recording, a montage or a manifest).

use std::io::Write;

use flate2::write::ZlibEncoder;
use flate2::Compression;
use oddball_io::IoError;

/// A MAT v5 file whose one compressed variable `x` is a 1 × `n` double matrix of zeros
/// (`n` × 8 bytes inflated, a few hundred bytes per MB compressed).
fn zip_bomb(n: u32) -> Vec<u8> {
    let mut header = vec![b' '; 116];
    header[..30].copy_from_slice(b"MATLAB 5.0 MAT-file, bomb test");
    header.extend_from_slice(&[0u8; 8]); // subsystem offset
    header.extend_from_slice(&0x0100u16.to_le_bytes());
    header.extend_from_slice(b"IM");
    let data_len = n as u64 * 8;
    let tag = |mi: u32, len: u32| [mi.to_le_bytes(), len.to_le_bytes()].concat();
    let mut inner: Vec<u8> = Vec::new();
    inner.extend(tag(6, 8)); // array flags
    inner.extend([6u8, 0, 0, 0, 0, 0, 0, 0]); // mxDOUBLE_CLASS
    inner.extend(tag(5, 8)); // dimensions
    inner.extend(1i32.to_le_bytes());
    inner.extend((n as i32).to_le_bytes());
    inner.extend([1u8, 0, 1, 0]); // small element: miINT8 name of 1 byte
    inner.extend([b'x', 0, 0, 0]);
    inner.extend(tag(9, data_len as u32)); // miDOUBLE real part
    let matrix_len = inner.len() as u64 + data_len;
    let mut z = ZlibEncoder::new(Vec::new(), Compression::best());
    z.write_all(&tag(14, matrix_len as u32)).unwrap();
    z.write_all(&inner).unwrap();
    let chunk = vec![0u8; 1 << 20];
    let mut left = data_len;
    while left > 0 {
        let k = left.min(chunk.len() as u64) as usize;
        z.write_all(&chunk[..k]).unwrap();
        left -= k as u64;
    }
    let compressed = z.finish().unwrap();
    let mut file = header;
    file.extend(tag(15, compressed.len() as u32));
    file.extend(&compressed);
    file
}

#[test]
fn a_mat_zip_bomb_is_refused_before_it_inflates() {
    let dir = tempfile::tempdir().unwrap();
    // 400 MB of zeros in well under a megabyte.
    let bomb = zip_bomb(50_000_000);
    assert!(bomb.len() < 1_000_000, "{} bytes", bomb.len());
    let path = dir.path().join("bomb.mat");
    std::fs::write(&path, &bomb).unwrap();
    let e = oddball_io::read_mat_file(&path).unwrap_err();
    let text = e.to_string();
    assert!(
        text.contains("zip bomb") && text.contains("400000"),
        "{text}"
    );
    assert!(matches!(e, IoError::InvalidField { .. }), "{e:?}");
    // Through the recording reader (inspect, evaluate) the same.
    let e = oddball_io::read(&path).unwrap_err();
    assert!(e.to_string().contains("zip bomb"), "{e}");
    // A variable of zeros that fits the budget (16 MiB + 40 × the file) still reads.
    let small = zip_bomb(1_000_000);
    let ok = dir.path().join("zeros.mat");
    std::fs::write(&ok, &small).unwrap();
    let f = oddball_io::read_mat_file(&ok).unwrap();
    assert_eq!(f.variables.len(), 1);
}

#[cfg(unix)]
#[test]
fn devices_and_links_to_them_are_refused_wherever_a_path_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("zero.csv");
    std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
    for p in [std::path::Path::new("/dev/zero"), link.as_path()] {
        let e = oddball_io::read(p).unwrap_err();
        assert!(matches!(e, IoError::NotRegular { .. }), "{e:?}");
        let e = oddball_io::montage::read_montage(p).unwrap_err();
        assert!(matches!(e, IoError::NotRegular { .. }), "{e:?}");
        let e = oddball_io::Manifest::load(p).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
    }
}
