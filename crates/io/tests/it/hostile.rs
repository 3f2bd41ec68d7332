//! Issue 13 at the reader boundary: every class of hostile or unusual file
//! ends in a one-line error naming the file (and row and column where there
//! is one), or in a recording that is right; real files are accepted.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use limpid_core::Recording;
use parquet::basic::{Compression, LogicalType, Repetition, TimeUnit, Type as Physical};
use parquet::data_type::{DoubleType, Int64Type};
use parquet::file::properties::WriterProperties;
use parquet::file::writer::SerializedFileWriter;
use parquet::schema::types::Type;

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

fn err(path: &Path) -> String {
    let e = limpid_io::read_recording(path).unwrap_err().to_string();
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(e.contains(&path.display().to_string()), "{e}");
    e
}

/// A small valid 3-D recording at 500 Hz.
fn recording(n: usize) -> Recording {
    let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.002).collect();
    let x: Vec<f64> = t.iter().map(|t| 0.3 + 0.01 * (5.0 * t).sin()).collect();
    let fx: Vec<f64> = x.iter().map(|x| 500.0 * (x - 0.3)).collect();
    Recording::new(
        "mem",
        vec!["t".into(), "x".into(), "fx".into()],
        vec![t, x, fx],
        2,
    )
    .unwrap()
}

/// A Parquet file of double columns written with `compression`.
fn write_parquet(path: &Path, rec: &Recording, compression: Compression) {
    let fields = rec
        .names()
        .iter()
        .map(|n| {
            Arc::new(
                Type::primitive_type_builder(n, Physical::DOUBLE)
                    .with_repetition(Repetition::REQUIRED)
                    .build()
                    .unwrap(),
            )
        })
        .collect();
    let schema = Arc::new(
        Type::group_type_builder("r")
            .with_fields(fields)
            .build()
            .unwrap(),
    );
    let props = Arc::new(
        WriterProperties::builder()
            .set_compression(compression)
            .build(),
    );
    let file = std::fs::File::create(path).unwrap();
    let mut w = SerializedFileWriter::new(file, schema, props).unwrap();
    let mut g = w.next_row_group().unwrap();
    for (_, c) in rec.columns() {
        let mut col = g.next_column().unwrap().unwrap();
        col.typed::<DoubleType>()
            .write_batch(c, None, None)
            .unwrap();
        col.close().unwrap();
    }
    g.close().unwrap();
    w.close().unwrap();
}

/// A null in an optional column is refused naming its row (rows count
/// from 1, as the recording's other messages for Parquet do) and column, in a later row group too, whether the
/// column is decoded straight into place (double) or through a batch (float).
#[test]
fn a_parquet_null_is_refused_by_row_and_column() {
    use parquet::data_type::FloatType;
    let d = tmp();
    for (physical, null_row) in [(Physical::DOUBLE, 7), (Physical::FLOAT, 130)] {
        let p = d.path().join(format!("null-{physical}.parquet"));
        let field = |name: &str, kind, repetition| {
            Arc::new(
                Type::primitive_type_builder(name, kind)
                    .with_repetition(repetition)
                    .build()
                    .unwrap(),
            )
        };
        let schema = Arc::new(
            Type::group_type_builder("r")
                .with_fields(vec![
                    field("t", Physical::DOUBLE, Repetition::REQUIRED),
                    field("x", physical, Repetition::OPTIONAL),
                ])
                .build()
                .unwrap(),
        );
        let props = Arc::new(WriterProperties::builder().build());
        let mut w =
            SerializedFileWriter::new(std::fs::File::create(&p).unwrap(), schema, props).unwrap();
        // two row groups of 100 rows; the null at 0-based sample null_row - 1
        for group in 0..2 {
            let mut g = w.next_row_group().unwrap();
            let t: Vec<f64> = (0..100).map(|i| (group * 100 + i) as f64 * 0.002).collect();
            let mut c = g.next_column().unwrap().unwrap();
            c.typed::<DoubleType>().write_batch(&t, None, None).unwrap();
            c.close().unwrap();
            let defs: Vec<i16> = (0..100)
                .map(|i| i16::from(group * 100 + i + 1 != null_row))
                .collect();
            let present = defs.iter().filter(|d| **d == 1).count();
            let mut c = g.next_column().unwrap().unwrap();
            if physical == Physical::DOUBLE {
                c.typed::<DoubleType>()
                    .write_batch(&vec![0.5; present], Some(&defs), None)
                    .unwrap();
            } else {
                c.typed::<FloatType>()
                    .write_batch(&vec![0.5; present], Some(&defs), None)
                    .unwrap();
            }
            c.close().unwrap();
            g.close().unwrap();
        }
        w.close().unwrap();
        let e = limpid_io::read_recording(&p).unwrap_err().to_string();
        assert!(
            e.contains(&format!("row {null_row}")) && e.contains("column x") && e.contains("null"),
            "{physical}: {e}"
        );
    }
}

#[test]
fn parquet_with_every_common_compression_reads_as_written() {
    let d = tmp();
    let rec = recording(500);
    for (name, c) in [
        ("zstd", Compression::ZSTD(Default::default())),
        ("gzip", Compression::GZIP(Default::default())),
        ("lz4", Compression::LZ4_RAW),
        ("brotli", Compression::BROTLI(Default::default())),
        ("snappy", Compression::SNAPPY),
    ] {
        let p = d.path().join(format!("{name}.parquet"));
        write_parquet(&p, &rec, c);
        let back = limpid_io::read_recording(&p).unwrap_or_else(|e| panic!("{name}: {e}"));
        for (column, values) in rec.columns() {
            assert_eq!(back.column(column).unwrap(), values, "{name}: {column}");
        }
    }
}

#[test]
fn parquet_timestamps_become_seconds_and_nested_columns_are_refused() {
    let d = tmp();
    let p = d.path().join("ts.parquet");
    let t = Arc::new(
        Type::primitive_type_builder("t", Physical::INT64)
            .with_repetition(Repetition::REQUIRED)
            .with_logical_type(Some(LogicalType::timestamp(false, TimeUnit::MILLIS)))
            .build()
            .unwrap(),
    );
    let x = Arc::new(
        Type::primitive_type_builder("x", Physical::DOUBLE)
            .with_repetition(Repetition::REQUIRED)
            .build()
            .unwrap(),
    );
    let schema = Arc::new(
        Type::group_type_builder("r")
            .with_fields(vec![t, x])
            .build()
            .unwrap(),
    );
    let mut w = SerializedFileWriter::new(
        std::fs::File::create(&p).unwrap(),
        schema,
        Arc::new(WriterProperties::builder().build()),
    )
    .unwrap();
    let mut g = w.next_row_group().unwrap();
    let stamps: Vec<i64> = (0..100).map(|i| 1_700_000_000_000 + 2 * i).collect();
    let mut c = g.next_column().unwrap().unwrap();
    c.typed::<Int64Type>()
        .write_batch(&stamps, None, None)
        .unwrap();
    c.close().unwrap();
    let mut c = g.next_column().unwrap().unwrap();
    c.typed::<DoubleType>()
        .write_batch(&[0.0; 100], None, None)
        .unwrap();
    c.close().unwrap();
    g.close().unwrap();
    w.close().unwrap();
    let rec = limpid_io::read_recording(&p).unwrap();
    assert!(
        (rec.sample_rate() - 500.0).abs() < 1e-9,
        "{}",
        rec.sample_rate()
    );
    assert_eq!(rec.t()[0], 0.0);
    assert!((rec.t()[99] - 0.198).abs() < 1e-12);
    assert!(rec.warnings()[0].contains("converted to seconds since the first sample"));

    // a struct column
    let p = d.path().join("nested.parquet");
    let leaf = Arc::new(
        Type::primitive_type_builder("a", Physical::DOUBLE)
            .with_repetition(Repetition::REQUIRED)
            .build()
            .unwrap(),
    );
    let group = Arc::new(
        Type::group_type_builder("s")
            .with_repetition(Repetition::REQUIRED)
            .with_fields(vec![leaf])
            .build()
            .unwrap(),
    );
    let schema = Arc::new(
        Type::group_type_builder("r")
            .with_fields(vec![group])
            .build()
            .unwrap(),
    );
    let w = SerializedFileWriter::new(
        std::fs::File::create(&p).unwrap(),
        schema,
        Arc::new(WriterProperties::builder().build()),
    )
    .unwrap();
    w.close().unwrap();
    let e = err(&p);
    assert!(e.contains("column s.a: a nested or repeated"), "{e}");
}

#[test]
fn unused_nested_and_text_parquet_columns_are_left_out_with_a_warning() {
    use parquet::data_type::{ByteArray, ByteArrayType};
    let d = tmp();
    let p = d.path().join("extra.parquet");
    let double = |name: &str| {
        Arc::new(
            Type::primitive_type_builder(name, Physical::DOUBLE)
                .with_repetition(Repetition::REQUIRED)
                .build()
                .unwrap(),
        )
    };
    let note = Arc::new(
        Type::primitive_type_builder("note", Physical::BYTE_ARRAY)
            .with_repetition(Repetition::REQUIRED)
            .with_logical_type(Some(LogicalType::String))
            .build()
            .unwrap(),
    );
    let pose = Arc::new(
        Type::group_type_builder("pose")
            .with_repetition(Repetition::REQUIRED)
            .with_fields(vec![double("a")])
            .build()
            .unwrap(),
    );
    let schema = Arc::new(
        Type::group_type_builder("r")
            .with_fields(vec![double("t"), pose, note, double("x")])
            .build()
            .unwrap(),
    );
    let mut w = SerializedFileWriter::new(
        std::fs::File::create(&p).unwrap(),
        schema,
        Arc::new(WriterProperties::builder().build()),
    )
    .unwrap();
    let n = 50;
    let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.01).collect();
    let x: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
    let mut g = w.next_row_group().unwrap();
    let mut c = g.next_column().unwrap().unwrap();
    c.typed::<DoubleType>().write_batch(&t, None, None).unwrap();
    c.close().unwrap();
    let mut c = g.next_column().unwrap().unwrap();
    c.typed::<DoubleType>()
        .write_batch(&vec![7.0; n], None, None)
        .unwrap();
    c.close().unwrap();
    let mut c = g.next_column().unwrap().unwrap();
    let words: Vec<ByteArray> = (0..n).map(|_| ByteArray::from("ok")).collect();
    c.typed::<ByteArrayType>()
        .write_batch(&words, None, None)
        .unwrap();
    c.close().unwrap();
    let mut c = g.next_column().unwrap().unwrap();
    c.typed::<DoubleType>().write_batch(&x, None, None).unwrap();
    c.close().unwrap();
    g.close().unwrap();
    w.close().unwrap();
    let rec = limpid_io::read_recording(&p).unwrap();
    assert_eq!(rec.names(), ["t", "x"]);
    assert_eq!(rec.column("x").unwrap(), &x[..]);
    let warnings = rec.warnings().join("\n");
    assert!(
        warnings.contains("column pose.a: a nested or repeated"),
        "{warnings}"
    );
    assert!(
        warnings.contains("column note: a String column"),
        "{warnings}"
    );
}

#[test]
fn corrupt_parquet_is_an_error_not_a_panic() {
    let d = tmp();
    let good = d.path().join("good.parquet");
    limpid_io::write_recording(&recording(2000), &good).unwrap();
    let whole = std::fs::read(&good).unwrap();
    let mut checked = 0;
    // every byte of the footer and of the first pages, in turn, set to 0xff
    for at in (0..whole.len()).filter(|i| *i < 300 || *i + 400 > whole.len()) {
        let mut b = whole.clone();
        b[at] = 0xff;
        let p = d.path().join("bad.parquet");
        std::fs::write(&p, &b).unwrap();
        if let Err(e) = limpid_io::read_recording(&p) {
            assert_eq!(e.to_string().lines().count(), 1, "{e}");
        }
        checked += 1;
    }
    assert!(checked > 500);
    let cut = d.path().join("cut.parquet");
    std::fs::write(&cut, &whole[..whole.len() - 10]).unwrap();
    err(&cut);
}

/// Columns are decoded in parallel; a file whose columns fail differently
/// gets one message, the first failing column's, on every read (it was
/// whichever column's task failed first: 1 read in 20 named another error).
#[test]
fn a_corrupt_parquet_file_gets_the_same_message_on_every_read() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/corpus/regressions/dictionary-page-claims-2e9-values.parquet");
    let messages: std::collections::BTreeSet<String> = (0..40)
        .map(|_| limpid_io::read_recording(&p).unwrap_err().to_string())
        .collect();
    assert_eq!(messages.len(), 1, "{messages:?}");
    let m = messages.first().unwrap();
    assert!(m.contains("dictionary page claims"), "{m}");
}

#[test]
fn one_huge_sample_is_refused_with_row_and_column_in_every_format() {
    let d = tmp();
    let mut rec = recording(300);
    let mut x = rec.column("x").unwrap().to_vec();
    x[200] = 1e307;
    // set_column skips the load-time check: the readers must catch it
    rec.set_column("x", x).unwrap();
    let csv = d.path().join("huge.csv");
    limpid_io::write_recording(&rec, &csv).unwrap();
    let e = err(&csv);
    assert!(
        e.contains("row 202, column x: implausible value 1e307"),
        "{e}"
    );
    let pq = d.path().join("huge.parquet");
    limpid_io::write_recording(&rec, &pq).unwrap();
    let e = err(&pq);
    assert!(
        e.contains("row 201, column x: implausible value 1e307"),
        "{e}"
    );
    let mat = d.path().join("huge.mat");
    std::fs::write(
        &mat,
        mat_file(&[("t", rec.t()), ("x", rec.column("x").unwrap())]),
    )
    .unwrap();
    let e = err(&mat);
    assert!(
        e.contains("row 201, column x: implausible value 1e307"),
        "{e}"
    );
}

/// A level-5 MAT-file of uncompressed double column vectors.
fn mat_file(vars: &[(&str, &[f64])]) -> Vec<u8> {
    let mut b = b"MATLAB 5.0 MAT-file, written by limpid's tests".to_vec();
    b.resize(116, b' ');
    b.extend_from_slice(&[0u8; 8]);
    b.extend_from_slice(&0x0100u16.to_le_bytes());
    b.extend_from_slice(b"IM");
    for (name, values) in vars {
        b.extend(mat_matrix(name, 6, &[values.len() as i32, 1], Some(values)));
    }
    b
}

/// One miMATRIX element of class `class` (6 double, 2 struct, 4 char, ...).
fn mat_matrix(name: &str, class: u32, dims: &[i32], values: Option<&[f64]>) -> Vec<u8> {
    fn element(kind: u32, data: &[u8]) -> Vec<u8> {
        let mut e = kind.to_le_bytes().to_vec();
        e.extend_from_slice(&(data.len() as u32).to_le_bytes());
        e.extend_from_slice(data);
        while !e.len().is_multiple_of(8) {
            e.push(0);
        }
        e
    }
    let mut body = element(6, &[class.to_le_bytes(), 0u32.to_le_bytes()].concat());
    body.extend(element(
        5,
        &dims
            .iter()
            .flat_map(|d| d.to_le_bytes())
            .collect::<Vec<u8>>(),
    ));
    body.extend(element(1, name.as_bytes()));
    if let Some(v) = values {
        body.extend(element(
            9,
            &v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>(),
        ));
    }
    element(14, &body)
}

#[test]
fn a_mat_column_that_is_a_struct_or_matrix_is_refused_by_name_others_are_warned() {
    let d = tmp();
    let t: Vec<f64> = (0..10).map(|i| i as f64 * 0.01).collect();
    let mut bytes = mat_file(&[("t", &t)]);
    bytes.extend(mat_matrix("x", 2, &[1, 1], None)); // a struct called x
    let p = d.path().join("struct.mat");
    std::fs::write(&p, &bytes).unwrap();
    let e = err(&p);
    assert!(
        e.contains("variable x (1 x 1), struct: a column must be a real numeric vector"),
        "{e}"
    );

    let mut bytes = mat_file(&[("t", &t)]);
    bytes.extend(mat_matrix("fx", 6, &[5, 2], Some(&[0.0; 10])));
    let p = d.path().join("matrix.mat");
    std::fs::write(&p, &bytes).unwrap();
    assert!(err(&p).contains("variable fx (5 x 2), double"));

    let mut bytes = mat_file(&[("t", &t), ("x", &t)]);
    bytes.extend(mat_matrix("comment", 4, &[1, 3], None));
    let p = d.path().join("extra.mat");
    std::fs::write(&p, &bytes).unwrap();
    let rec = limpid_io::read_recording(&p).unwrap();
    assert_eq!(rec.warnings().len(), 1);
    assert!(
        rec.warnings()[0].contains("comment (1 x 3), char"),
        "{:?}",
        rec.warnings()
    );
}

#[test]
fn special_files_and_gaps_and_units() {
    // a FIFO and a device are refused before they are opened (no blocking, no endless read)
    let e = limpid_io::read_recording("/dev/zero")
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a regular file"), "{e}");
    let e = limpid_io::read_recording("/dev/zero.mat")
        .unwrap_err()
        .to_string();
    assert!(e.contains("/dev/zero.mat"), "{e}");
    let d = tmp();
    let fifo = d.path().join("fifo.csv");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if made.is_ok_and(|s| s.success()) {
        let e = err(&fifo);
        assert!(e.contains("not a regular file"), "{e}");
    }
    // only the perturbation windows kept: gaps where the trial changes are allowed
    let mut csv = String::from("t,x,fx,trial\n");
    for trial in 0..3 {
        for i in 0..50 {
            let t = trial as f64 * 10.0 + i as f64 * 0.002;
            csv.push_str(&format!("{t},{},{},{trial}\n", 0.3, 1.0));
        }
    }
    let p = d.path().join("windows.csv");
    std::fs::write(&p, &csv).unwrap();
    let rec = limpid_io::read_recording(&p).unwrap();
    assert!((rec.sample_rate() - 500.0).abs() < 1e-6);
    // the same gap inside a trial is not uniform sampling
    let p = d.path().join("gap.csv");
    std::fs::write(&p, csv.replace(",1\n", ",0\n")).unwrap();
    assert!(err(&p).contains("non-uniform sampling"));
    // t in milliseconds is accepted with a warning
    let mut ms = String::from("t,x,fx\n");
    for i in 0..100 {
        ms.push_str(&format!("{},{},{}\n", 2 * i, 0.3, 1.0));
    }
    let p = d.path().join("ms.csv");
    std::fs::write(&p, ms).unwrap();
    let rec = limpid_io::read_recording(&p).unwrap();
    assert!(
        rec.warnings().iter().any(|w| w.contains("milliseconds")),
        "{:?}",
        rec.warnings()
    );
}

#[test]
fn a_header_of_100k_columns_is_checked_in_linear_time() {
    let d = tmp();
    let n = 100_000;
    let mut header: Vec<String> = (0..n).map(|i| format!("c{i}")).collect();
    header[0] = "t".into();
    header[n - 1] = "c5".into(); // duplicate of the 6th
    let row: Vec<&str> = vec!["0"; n];
    let text = format!("{}\n{}\n", header.join(","), row.join(","));
    let p: PathBuf = d.path().join("wide.csv");
    std::fs::write(&p, text).unwrap();
    let start = std::time::Instant::now();
    let e = err(&p);
    assert!(
        e.contains("duplicate column name (columns 6 and 100000)"),
        "{e}"
    );
    println!("100k columns checked in {:?}", start.elapsed());
}
