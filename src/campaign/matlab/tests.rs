//! The fixtures of `scripts/make_mat_fixtures.py` read back to the values the script wrote,
//! and the refusals' messages.

use super::*;

pub(super) const PLAIN: &[u8] = include_bytes!("../../../tests/data/matlab/plain.mat");
pub(super) const PLAIN_Z: &[u8] = include_bytes!("../../../tests/data/matlab/plain_z.mat");
pub(super) const DSPACE: &[u8] = include_bytes!("../../../tests/data/matlab/dspace.mat");
pub(super) const RASTERS: &[u8] = include_bytes!("../../../tests/data/matlab/dspace_rasters.mat");
pub(super) const BIG_ENDIAN: &[u8] = include_bytes!("../../../tests/data/matlab/bigendian.mat");
const LITTLE_ENDIAN: &[u8] = include_bytes!("../../../tests/data/matlab/littleendian.mat");
const V4: &[u8] = include_bytes!("../../../tests/data/matlab/v4.mat");
const V73: &[u8] = include_bytes!("../../../tests/data/matlab/v73.mat");

fn read(bytes: &[u8]) -> MatFile {
    read_mat(bytes, "test.mat").unwrap()
}

fn err(result: Result<impl std::fmt::Debug, MatError>) -> String {
    result.unwrap_err().to_string()
}

fn assert_close(got: &[f64], want: impl Iterator<Item = f64>, tol: f64) {
    let want: Vec<f64> = want.collect();
    assert_eq!(got.len(), want.len());
    for (k, (g, w)) in got.iter().zip(&want).enumerate() {
        assert!((g - w).abs() <= tol, "sample {k}: {g} != {w}");
    }
}

fn check_plain(m: &MatFile) {
    assert_close(
        &m.signal("accel").unwrap(),
        (0..100).map(|k| (0.1 * k as f64).sin()),
        1e-15,
    );
    for j in 1..=3 {
        let want = (0..50).map(move |i| 100.0 * j as f64 + i as f64 + 0.25);
        assert_close(&m.signal(&format!("data:{j}")).unwrap(), want, 0.0);
    }
    assert_eq!(
        m.signal("accel:1").unwrap().len(),
        100,
        "a vector is its own column 1"
    );
    assert_close(
        &m.signal("counts").unwrap(),
        (-5..5).map(|k| 1000.0 * k as f64),
        0.0,
    );
    assert_eq!(
        m.variable("label").and_then(MatValue::text),
        Some("Xgf table displacement")
    );
    let Some(MatValue::Cell { dims, elements }) = m.variable("notes") else {
        panic!("notes is a cell")
    };
    assert_eq!(dims, &[1, 2]);
    assert_eq!(elements[0], MatValue::Char("first".into()));
    assert_eq!(
        elements[1],
        MatValue::Numeric {
            dims: vec![1, 3],
            data: vec![1.0, 2.0, 3.0]
        }
    );
}

#[test]
fn plain_file_reads_the_values_written() {
    check_plain(&read(PLAIN));
}

#[test]
fn compressed_file_reads_the_same_values() {
    let (plain, packed) = (read(PLAIN), read(PLAIN_Z));
    check_plain(&packed);
    assert_eq!(plain.variables, packed.variables);
}

#[test]
fn plain_listing_names_vectors_and_matrix_columns() {
    let columns: Vec<(String, usize)> = read(PLAIN)
        .signals()
        .into_iter()
        .map(|s| (s.column, s.len))
        .collect();
    let want = [
        ("accel", 100),
        ("data:1", 50),
        ("data:2", 50),
        ("data:3", 50),
        ("counts", 10),
    ];
    assert_eq!(columns, want.map(|(c, n)| (c.to_string(), n)));
}

#[test]
fn plain_refusals_say_what_the_variable_is() {
    let m = read(PLAIN);
    let e = err(m.signal("data"));
    assert!(
        e.contains("50x3") && e.contains("`data:1` to `data:3`"),
        "{e}"
    );
    assert!(err(m.signal("data:4")).contains("columns are 1 to 3"));
    assert!(err(m.signal("z")).contains("complex"));
    assert!(err(m.signal("sp")).contains("sparse matrix"));
    assert!(err(m.signal("label")).contains("is text (\"Xgf table displacement\")"));
    let e = err(m.signal("speed"));
    assert!(
        e.starts_with("test.mat: no variable or signal `speed`"),
        "{e}"
    );
    assert!(
        e.contains("`accel`, `data:1`, `data:2`, `data:3`, `counts`"),
        "{e}"
    );
}

#[test]
fn dspace_time_and_signals_by_name_and_path() {
    let m = read(DSPACE);
    assert_close(
        &m.signal("rec.X.Data").unwrap(),
        (0..200).map(|k| k as f64 / 1000.0),
        0.0,
    );
    assert_close(
        &m.signal("Agf").unwrap(),
        (0..200).map(|k| 0.5 * k as f64),
        0.0,
    );
    assert_close(
        &m.signal("Model Root/Plant/Agf").unwrap(),
        (0..200).map(|k| 0.5 * k as f64),
        0.0,
    );
    let plant = (0..200).map(|k| 0.01 * (0.05 * k as f64).cos());
    assert_close(&m.signal("Model Root/Plant/Xgf").unwrap(), plant, 1e-17);
    assert_close(
        &m.signal("Model Root/Controller/Xgf").unwrap(),
        (0..200).map(|k| -(k as f64)),
        0.0,
    );
}

#[test]
fn dspace_name_of_two_signals_is_ambiguous() {
    let e = err(read(DSPACE).signal("Xgf"));
    assert!(e.contains("`Xgf` names 2 dSPACE signals"), "{e}");
    assert!(
        e.contains("\"Model Root/Plant/Xgf\", \"Model Root/Controller/Xgf\""),
        "{e}"
    );
}

#[test]
fn dspace_listing_gives_time_units_and_unique_columns() {
    let signals = read(DSPACE).signals();
    let columns: Vec<&str> = signals.iter().map(|s| s.column.as_str()).collect();
    assert_eq!(
        columns,
        [
            "rec.X.Data",
            "Model Root/Plant/Xgf",
            "Agf",
            "Model Root/Controller/Xgf"
        ]
    );
    assert!(signals.iter().all(|s| s.len == 200));
    assert_eq!(
        signals[0].kind,
        SignalKind::DspaceTime {
            recording: "rec".into()
        }
    );
    let kind = SignalKind::DspaceSignal {
        recording: "rec".into(),
        path: "Model Root/Plant/Agf".into(),
        unit: Some("m/s^2".into()),
        time: "rec.X.Data".into(),
    };
    assert_eq!(signals[2].kind, kind);
    let e = err(read(DSPACE).signal("rec"));
    assert!(
        e.contains(
            "is a dSPACE recording; name one of its signals (`rec.X.Data`, `Model Root/Plant/Xgf`"
        ),
        "{e}"
    );
}

#[test]
fn dspace_struct_array_elements_by_index() {
    let m = read(DSPACE);
    assert_eq!(m.signal("rec.Y(2).Data").unwrap(), m.signal("Agf").unwrap());
    assert_eq!(
        m.variable("rec")
            .and_then(|r| r.field("Description"))
            .and_then(MatValue::text),
        Some("shaketable fixture")
    );
    assert!(err(m.signal("rec.Y.Data")).contains("no variable or signal `rec.Y.Data`"));
    assert!(err(m.signal("rec.Y(4).Data")).contains("no variable or signal"));
}

#[test]
fn dspace_time_bases_follow_x_index() {
    let m = read(RASTERS);
    let listed: Vec<(String, usize)> = m.signals().into_iter().map(|s| (s.column, s.len)).collect();
    let want = [
        ("rasters.X(1).Data", 100),
        ("rasters.X(2).Data", 10),
        ("Fast", 100),
        ("Slow", 10),
    ];
    assert_eq!(listed, want.map(|(c, n)| (c.to_string(), n)));
    let times: Vec<String> = m
        .signals()
        .into_iter()
        .filter_map(|s| match s.kind {
            SignalKind::DspaceSignal { time, .. } => Some(time),
            _ => None,
        })
        .collect();
    assert_eq!(times, ["rasters.X(1).Data", "rasters.X(2).Data"]);
    assert_close(
        &m.signal("rasters.X(2).Data").unwrap(),
        (0..10).map(|k| k as f64 / 100.0),
        0.0,
    );
    assert_close(
        &m.signal("Model Root/Slow").unwrap(),
        (0..10).map(|k| -(k as f64)),
        0.0,
    );
}

#[test]
fn both_byte_orders_and_narrow_storage_types() {
    let (big, little) = (read(BIG_ENDIAN), read(LITTLE_ENDIAN));
    assert_eq!(big.variables, little.variables);
    assert_eq!(big.signal("accel_be").unwrap(), [1.5, -2.25, 3.0]);
    assert_eq!(big.signal("small").unwrap(), [1.0, -2.0, 300.0]);
    assert_eq!(big.signal("bytes").unwrap(), [7.0, 255.0]);
    assert_eq!(big.variable("unit").and_then(MatValue::text), Some("m/s2"));
}

#[test]
fn other_formats_are_refused_by_name() {
    let e = err(read_mat(V4, "old.mat"));
    assert_eq!(
        e,
        "old.mat: level 4 MAT files are not supported; save with -v7 or -v6"
    );
    let e = err(read_mat(V73, "new.mat"));
    assert_eq!(
        e,
        "new.mat: MATLAB v7.3 (HDF5) MAT-files are not supported; save with -v7 or -v6"
    );
    let mut hdf5_only = vec![b' '; 512];
    hdf5_only.extend_from_slice(b"\x89HDF\r\n\x1a\n");
    assert!(matches!(
        read_mat(&hdf5_only, "h.mat"),
        Err(MatError::V73 { .. })
    ));
    assert!(
        err(read_mat(b"time,accel\n0,1\n", "a.mat")).contains("shorter than the 128-byte header")
    );
    let mut no_mark = PLAIN.to_vec();
    no_mark[126..128].copy_from_slice(b"XX");
    assert!(err(read_mat(&no_mark, "a.mat")).contains("no endian mark IM or MI at byte 126"));
}

fn matlab_written(name: &str) -> MatFile {
    let path = format!(
        "{}/tests/data/matlab/matlab-written/{name}",
        env!("CARGO_MANIFEST_DIR")
    );
    read_mat(&std::fs::read(path).unwrap(), name).unwrap()
}

fn number(value: &MatValue) -> f64 {
    match value {
        MatValue::Numeric { data, .. } if data.len() == 1 => data[0],
        other => panic!("not a scalar: {other:?}"),
    }
}

#[test]
fn matlab_written_big_endian_matrix_stored_as_bytes() {
    let m = matlab_written("testmatrix_6.1_SOL2.mat");
    assert_eq!(m.signal("testmatrix:1").unwrap(), [1.0, 2.0, 3.0]);
    assert_eq!(m.signal("testmatrix:5").unwrap(), [5.0, 0.0, 0.0]);
    assert_eq!(
        matlab_written("miuint32_for_miint32.mat")
            .signal("an_array")
            .unwrap(),
        (0..10).map(f64::from).collect::<Vec<_>>()
    );
}

#[test]
fn matlab_written_structs_and_cells() {
    let m = matlab_written("teststructarr_6.1_SOL2.mat");
    let Some(MatValue::Struct {
        dims,
        fields,
        elements,
    }) = m.variable("teststructarr")
    else {
        panic!()
    };
    assert_eq!(
        (dims.as_slice(), fields.as_slice()),
        (
            [1, 2].as_slice(),
            ["one".to_string(), "two".to_string()].as_slice()
        )
    );
    assert_eq!(
        (number(&elements[0][0]), number(&elements[0][1])),
        (1.0, 2.0)
    );
    assert_eq!(
        (elements[1][0].text(), elements[1][1].text()),
        (Some("number 1"), Some("number 2"))
    );
    let m = matlab_written("teststruct_7.4_GLNX86.mat");
    let want = [2f64.sqrt(), std::f64::consts::E, std::f64::consts::PI];
    assert_close(
        &m.signal("teststruct.doublefield").unwrap(),
        want.into_iter(),
        1e-15,
    );
    assert_eq!(
        m.value_at("teststruct.stringfield")
            .and_then(MatValue::text),
        Some("Rats live on no evil star.")
    );
    assert!(err(m.signal("teststruct.complexfield")).contains("complex numeric array"));
    let m = matlab_written("testcellnest_7.4_GLNX86.mat");
    let Some(MatValue::Cell { elements, .. }) = m.variable("testcellnest") else {
        panic!()
    };
    let MatValue::Cell {
        elements: inner, ..
    } = &elements[1]
    else {
        panic!()
    };
    let MatValue::Cell {
        elements: innermost,
        ..
    } = &inner[2]
    else {
        panic!()
    };
    assert_eq!(
        (
            number(&elements[0]),
            number(&inner[1]),
            number(&innermost[1])
        ),
        (1.0, 3.0, 5.0)
    );
}

#[test]
fn matlab_written_v73_is_refused() {
    let path = format!(
        "{}/tests/data/matlab/matlab-written/testhdf5_7.4_GLNX86.mat",
        env!("CARGO_MANIFEST_DIR")
    );
    assert!(matches!(
        read_mat(&std::fs::read(path).unwrap(), "h.mat"),
        Err(MatError::V73 { .. })
    ));
}
