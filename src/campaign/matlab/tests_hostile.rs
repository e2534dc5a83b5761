//! Hostile input: truncation, sizes past the end, absurd dimensions, deep nesting, zlib
//! bombs, wrong element types, and mutated fixtures (proptest): errors, never panics.

use super::tests::{BIG_ENDIAN, DSPACE, PLAIN, PLAIN_Z, RASTERS};
use super::*;
use proptest::prelude::*;
use std::io::Write;

/// One little-endian data element padded to 8 bytes.
fn element(mi_type: u32, data: &[u8]) -> Vec<u8> {
    let mut out = [mi_type.to_le_bytes(), (data.len() as u32).to_le_bytes()].concat();
    out.extend_from_slice(data);
    out.resize(out.len().next_multiple_of(8), 0);
    out
}

/// An miMATRIX of `class` with `dims`, `name` and the class-specific elements `rest`.
fn matrix(class: u32, dims: &[i32], name: &str, rest: &[u8]) -> Vec<u8> {
    let dims: Vec<u8> = dims.iter().flat_map(|d| d.to_le_bytes()).collect();
    let body = [
        element(6, &[class as u8, 0, 0, 0, 0, 0, 0, 0]),
        element(5, &dims),
        element(1, name.as_bytes()),
        rest.to_vec(),
    ];
    element(14, &body.concat())
}

fn doubles(values: &[f64]) -> Vec<u8> {
    element(
        9,
        &values
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect::<Vec<u8>>(),
    )
}

/// A file of the fixture's header followed by `elements`.
fn file(elements: &[Vec<u8>]) -> Vec<u8> {
    [PLAIN[..128].to_vec(), elements.concat()].concat()
}

fn zlib(data: &[u8]) -> Vec<u8> {
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    z.write_all(data).unwrap();
    z.finish().unwrap()
}

fn err(bytes: &[u8]) -> String {
    read_mat(bytes, "x.mat").unwrap_err().to_string()
}

#[test]
fn hand_built_file_reads() {
    let bytes = file(&[matrix(6, &[1, 2], "v", &doubles(&[1.0, 2.0]))]);
    assert_eq!(
        read_mat(&bytes, "x.mat").unwrap().signal("v").unwrap(),
        [1.0, 2.0]
    );
    let cube = file(&[matrix(6, &[2, 1, 2], "c", &doubles(&[1.0, 2.0, 3.0, 4.0]))]);
    let e = read_mat(&cube, "x.mat")
        .unwrap()
        .signal("c")
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "x.mat: `c`: is a 2x1x2 numeric array, neither a vector nor a 2-D matrix"
    );
}

#[test]
fn nameless_subsystem_data_is_not_a_variable() {
    let subsystem = matrix(9, &[1, 8], "", &element(2, &[1; 8]));
    let bytes = file(&[matrix(6, &[1, 1], "v", &doubles(&[2.0])), subsystem]);
    let m = read_mat(&bytes, "x.mat").unwrap();
    assert_eq!(m.variables.len(), 1);
    assert_eq!(m.signals().len(), 1);
}

#[test]
fn every_truncation_is_an_error_or_a_cut_between_variables() {
    for fixture in [PLAIN, PLAIN_Z, DSPACE, RASTERS, BIG_ENDIAN] {
        let whole = read_mat(fixture, "whole.mat").unwrap().variables;
        for len in 0..fixture.len() {
            if let Ok(cut) = read_mat(&fixture[..len], "cut.mat") {
                assert!(
                    whole.starts_with(&cut.variables),
                    "cut at {len} read other values"
                );
            }
        }
    }
}

#[test]
fn a_file_cut_inside_a_variable_names_it() {
    let samples: Vec<f64> = (0..1000).map(f64::from).collect();
    let first = matrix(6, &[1, 2], "v", &doubles(&[1.0, 2.0]));
    let accel = matrix(6, &[1, 1000], "accel", &doubles(&samples));
    let at = 128 + first.len();
    let whole = file(&[first.clone(), accel.clone()]);
    let e = err(&whole[..whole.len() - 3000]);
    assert!(
        e.starts_with(&format!("x.mat: variable `accel`, byte {at}: element of ")),
        "{e}"
    );
    // compressed: the name is in the first inflated bytes of a stream cut short
    let packed = file(&[first, element(15, &zlib(&accel))]);
    let e = err(&packed[..packed.len() - 40]);
    assert!(e.contains("variable `accel`"), "{e}");
    // a cut inside the tag itself leaves no name to give
    let e = err(&whole[..at + 6]);
    assert!(!e.contains("variable"), "{e}");
}

#[test]
fn size_past_the_end_names_the_offset() {
    let mut bytes = file(&[]);
    bytes.extend_from_slice(&[14, 0, 0, 0, 0xf0, 0xff, 0xff, 0xff]);
    assert_eq!(
        err(&bytes),
        "x.mat: byte 128: element of 4294967280 bytes but only 0 remain"
    );
}

#[test]
fn absurd_dimensions_are_refused_before_allocating() {
    let e = err(&file(&[matrix(
        6,
        &[65536, 65536, 65536, 65536],
        "v",
        &doubles(&[1.0]),
    )]));
    assert!(
        e.contains("variable `v`") && e.contains("absurd dimensions"),
        "{e}"
    );
    let e = err(&file(&[matrix(6, &[1000, 1000], "v", &doubles(&[1.0]))]));
    assert!(e.contains("1 values for dimensions [1000, 1000]"), "{e}");
    let e = err(&file(&[matrix(1, &[1 << 30, 4], "c", &[])]));
    assert!(e.contains("4294967296 cells do not fit"), "{e}");
    let names = [element(5, &32i32.to_le_bytes()), element(1, &[b'a'; 32])].concat();
    let e = err(&file(&[matrix(2, &[1 << 30, 1], "s", &names)]));
    assert!(
        e.contains("1073741824 elements of 1 fields do not fit"),
        "{e}"
    );
    assert!(err(&file(&[matrix(6, &[-1, 2], "v", &[])])).contains("a negative dimension"));
}

#[test]
fn deep_nesting_is_refused() {
    let mut value = matrix(6, &[1, 1], "", &doubles(&[1.0]));
    for _ in 0..40 {
        value = matrix(1, &[1, 1], "", &value);
    }
    let bytes = file(&[value]);
    let e = err(&bytes);
    assert!(
        e.contains("nested deeper than 32") && e.contains("variable `{1}{1}"),
        "{e}"
    );
}

#[test]
fn zlib_bomb_stops_at_the_budget() {
    let zeros = matrix(6, &[1, 1 << 17], "z", &doubles(&vec![0.0; 1 << 17]));
    let bytes = file(&[element(15, &zlib(&zeros))]);
    let e = read_mat_bounded(&bytes, "bomb.mat", 4096)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "bomb.mat: variable `z`, byte 128: compressed variables inflate to more than 4096 bytes in all"
    );
    assert_eq!(
        read_mat(&bytes, "ok.mat")
            .unwrap()
            .signal("z")
            .unwrap()
            .len(),
        1 << 17
    );
    let mut broken = zlib(&zeros);
    broken[10] ^= 0xff;
    assert!(err(&file(&[element(15, &broken)])).contains("does not inflate"));
}

#[test]
fn wrong_element_types_name_the_variable_and_offset() {
    assert!(err(&file(&[doubles(&[1.0])])).contains("byte 128: top-level element of type 9"));
    let flags_as_double = element(
        14,
        &[doubles(&[6.0]), element(5, &[1, 0, 0, 0, 1, 0, 0, 0])].concat(),
    );
    assert!(
        err(&file(&[flags_as_double])).contains("byte 136: the array flags stored as data type 9")
    );
    let names = [
        element(5, &8i32.to_le_bytes()),
        element(1, b"f\0\0\0\0\0\0\0"),
    ]
    .concat();
    let field = matrix(6, &[1, 1], "", &element(18, &[0; 8]));
    let e = err(&file(&[matrix(2, &[1, 1], "s", &[names, field].concat())]));
    assert!(
        e.starts_with("x.mat: variable `s.f`, byte ")
            && e.contains("numeric data stored as data type 18"),
        "{e}"
    );
    let compressed_number = element(15, &zlib(&doubles(&[1.0])));
    let e = err(&file(&[compressed_number]));
    let want = "byte 0 of the compressed variable at byte 128: a compressed variable stored as data type 9";
    assert!(e.contains(want), "{e}");
}

/// A compressed fixture rewritten uncompressed, so that mutations reach the parser
/// rather than the zlib checksum.
fn inflated(bytes: &[u8]) -> Vec<u8> {
    let mut out = bytes[..128].to_vec();
    let mut pos = 128;
    while pos + 8 <= bytes.len() {
        let n = u32::from_le_bytes(bytes[pos + 4..pos + 8].try_into().unwrap()) as usize;
        let mut z = flate2::read::ZlibDecoder::new(&bytes[pos + 8..pos + 8 + n]);
        std::io::Read::read_to_end(&mut z, &mut out).unwrap();
        pos += 8 + n;
    }
    out
}

#[test]
fn inflated_fixtures_read_the_same() {
    for fixture in [PLAIN_Z, DSPACE] {
        let (packed, plain) = (
            read_mat(fixture, "z.mat"),
            read_mat(&inflated(fixture), "z.mat"),
        );
        assert_eq!(packed.unwrap().variables, plain.unwrap().variables);
    }
}

/// A fixture with some bytes replaced, one aligned 32-bit word overwritten, and a cut.
fn mutate(bytes: &[u8], flips: &[(usize, u8)], word: Option<(usize, u32)>, cut: usize) -> Vec<u8> {
    let mut out = bytes.to_vec();
    for &(at, b) in flips {
        let n = out.len();
        out[at % n] = b;
    }
    if let Some((at, w)) = word {
        let at = (at % (out.len() / 4)) * 4;
        out[at..at + 4].copy_from_slice(&w.to_le_bytes());
    }
    out.truncate(out.len() - cut % 64);
    out
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4000, ..ProptestConfig::default() })]
    #[test]
    fn mutated_fixtures_never_panic(
        which in 0usize..7,
        flips in proptest::collection::vec((any::<usize>(), any::<u8>()), 0..6),
        word in proptest::option::of((any::<usize>(), any::<u32>())),
        cut in any::<usize>(),
    ) {
        let fixture = match which {
            5 => inflated(DSPACE),
            6 => inflated(PLAIN_Z),
            k => [PLAIN, PLAIN_Z, DSPACE, RASTERS, BIG_ENDIAN][k].to_vec(),
        };
        let bytes = mutate(&fixture, &flips, word, cut);
        if let Ok(m) = read_mat(&bytes, "mutant.mat") {
            for s in m.signals() {
                let _ = m.signal(&s.column);
            }
            let _ = m.signal("Xgf");
        }
    }
}
