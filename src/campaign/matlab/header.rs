//! The 128-byte header: which MAT-file version this is, and its byte order.

use super::MatError;

/// 116 bytes of text, 8 of subsystem offset, 2 of version, 2 of endian mark.
pub(super) const HEADER_LEN: usize = 128;
/// Where a v7.3 file (an HDF5 file with a 512-byte user block) has the HDF5 signature.
const HDF5_AT: usize = 512;
/// The 8-byte HDF5 format signature.
const HDF5_SIGNATURE: &[u8] = b"\x89HDF\r\n\x1a\n";

/// Refuse what is not level 5; return whether the file is big-endian ("MI").
pub(super) fn check_header(bytes: &[u8], file: &str) -> Result<bool, MatError> {
    let not_mat = |why: String| MatError::NotMat {
        file: file.to_string(),
        why,
    };
    if bytes.get(HDF5_AT..HDF5_AT + HDF5_SIGNATURE.len()) == Some(HDF5_SIGNATURE)
        || bytes.starts_with(b"MATLAB 7.3 MAT-file")
    {
        return Err(MatError::V73 {
            file: file.to_string(),
        });
    }
    // A level-4 file starts with its type word MOPT (< 5000), so some of bytes 0..4 are zero;
    // level 5 starts with text, whose first 4 bytes the format requires to be non-zero.
    if bytes.len() >= 4 && bytes[..4].contains(&0) {
        return Err(MatError::Level4 {
            file: file.to_string(),
        });
    }
    if bytes.len() < HEADER_LEN {
        return Err(not_mat(format!(
            "{} bytes, shorter than the 128-byte header",
            bytes.len()
        )));
    }
    let big_endian = match &bytes[126..128] {
        b"IM" => false,
        b"MI" => true,
        _ => return Err(not_mat("no endian mark IM or MI at byte 126".into())),
    };
    let v = [bytes[124], bytes[125]];
    match if big_endian {
        u16::from_be_bytes(v)
    } else {
        u16::from_le_bytes(v)
    } {
        0x0100 => Ok(big_endian),
        0x0200 => Err(MatError::V73 {
            file: file.to_string(),
        }),
        other => Err(not_mat(format!(
            "version 0x{other:04x} at byte 124 (level 5 is 0x0100)"
        ))),
    }
}
