//! LAS and LAZ on real files (fixtures/formats, from laspy's test data; see LICENSES.md there):
//! counts, georeferenced coordinates as laspy reads them, the compressed and uncompressed copies
//! of a file giving the same points, a registration from a LAZ file, and hostile headers, chunk
//! tables and layer sizes giving errors that say what is wrong.

use arps::io::{detect_format, read_point_cloud, Format};
use arps::transform::{euler_xyz, from_rotation_translation, rotation_error_deg};
use arps::{Options, PointCloud, Registrar};
use nalgebra::Vector3;

fn fixture(name: &str) -> Vec<u8> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/formats").join(name);
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn read(name: &str) -> PointCloud {
    read_point_cloud(&fixture(name), name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn err(bytes: &[u8], name: &str) -> String {
    match read_point_cloud(bytes, name) {
        Ok(c) => panic!("{name}: expected an error, read {} points", c.len()),
        Err(e) => e.to_string(),
    }
}

#[track_caller]
fn has(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "expected {p:?} in: {msg}");
    }
}

/// Point `i` in the file's frame is within `tol` of `want` (laspy's `x, y, z`).
#[track_caller]
fn at(c: &PointCloud, i: usize, want: [f64; 3], tol: f64) {
    let p = c.point_f64(i);
    assert!((0..3).all(|k| (p[k] - want[k]).abs() <= tol), "point {i}: {p:?}, laspy {want:?}");
}

/// (file, points, first, last, min, max) as laspy 2.5.4 reads them.
type Expected = (&'static str, usize, [f64; 3], [f64; 3], [f64; 3], [f64; 3]);

const SIMPLE: [[f64; 3]; 4] = [
    [637012.24, 849028.31, 431.66],
    [637342.85, 853240.32, 423.92],
    [635619.85, 848899.70, 406.59],
    [638982.55, 853535.43, 586.38],
];
const EVLR: [[f64; 3]; 4] = [
    [1694510.3869346841, 1816497.966263977, 5598.3596128149675],
    [1694291.6363326558, 1816493.0662305846, 5597.089652537912],
    [1694038.4456374517, 1816492.7062700584, 5592.7499174683535],
    [1694539.677014474, 1816497.9762624602, 5599.069686751426],
];

const FILES: [Expected; 5] = [
    ("simple.las", 1065, SIMPLE[0], SIMPLE[1], SIMPLE[2], SIMPLE[3]),
    ("simple.laz", 1065, SIMPLE[0], SIMPLE[1], SIMPLE[2], SIMPLE[3]),
    ("1_4_w_evlr.las", 1000, EVLR[0], EVLR[1], EVLR[2], EVLR[3]),
    ("1_4_w_evlr.laz", 1000, EVLR[0], EVLR[1], EVLR[2], EVLR[3]),
    ("simple.copc.laz", 1065, [636145.60, 849170.47, 428.15], [638314.34, 852793.54, 419.65], SIMPLE[2], SIMPLE[3]),
];

#[test]
fn las_and_laz_give_the_coordinates_laspy_reads() {
    for (name, n, first, last, lo, hi) in FILES {
        let c = read(name);
        assert_eq!(c.len(), n, "{name}");
        // map-grid coordinates (1.7e6) keep their shape: an origin near the points, f32 offsets
        assert!(!c.origin_is_zero(), "{name}: origin {:?}", c.origin);
        let tol = 2e-3;
        at(&c, 0, first, tol);
        at(&c, n - 1, last, tol);
        let (mut min, mut max) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for i in 0..n {
            let p = c.point_f64(i);
            for k in 0..3 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
            }
        }
        assert!(
            (0..3).all(|k| (min[k] - lo[k]).abs() <= tol && (max[k] - hi[k]).abs() <= tol),
            "{name}: {min:?} {max:?}"
        );
        // the format by extension and by its signature
        assert_eq!(detect_format(&fixture(name), name).unwrap(), Format::Las);
        assert_eq!(detect_format(&fixture(name), "upload").unwrap(), Format::Las, "{name} sniffed");
        assert_eq!(read_point_cloud(&fixture(name), "upload").unwrap(), c, "{name} sniffed");
    }
}

#[test]
fn a_compressed_file_gives_the_points_of_its_uncompressed_copy() {
    // point format 3 (LASzip's point-wise chunks) and 6 (layered chunks, X, Y, Z decoded alone)
    assert_eq!(read("simple.laz"), read("simple.las"));
    assert_eq!(read("1_4_w_evlr.laz"), read("1_4_w_evlr.las"));
    // the COPC file holds the same survey in another order
    let (a, b) = (read("simple.copc.laz"), read("simple.las"));
    let key = |c: &PointCloud| {
        let mut v: Vec<[i64; 3]> = (0..c.len()).map(|i| c.point_f64(i).map(|x| (x * 100.0).round() as i64)).collect();
        v.sort_unstable();
        v
    };
    assert_eq!(key(&a), key(&b));
}

#[test]
fn a_laz_survey_registers_onto_itself_moved() {
    // the source is the LAZ file as read; the target that survey moved by a known motion (in the
    // file's frame: map-grid coordinates) and written as PLY with doubles
    let source = read("1_4_w_evlr.laz");
    // turned about the survey's centre
    let c = Vector3::from(source.origin) + Vector3::from(source.centroid());
    let turn = from_rotation_translation(&euler_xyz(0.05, -0.08, 0.3), &Vector3::new(12.0, -7.5, 1.2));
    let gt = nalgebra::Matrix4::new_translation(&c) * turn * nalgebra::Matrix4::new_translation(&-c);
    let target = source.transformed(&gt);
    let target = read_point_cloud(&arps::io::write_ply_binary(&target), "moved.ply").unwrap();
    let r = Registrar::with_default_model().unwrap().register(&source, &target, &Options::default()).unwrap();
    let t = &r.T_target_source;
    assert!(rotation_error_deg(t, &gt) < 0.5, "rotation off by {}", rotation_error_deg(t, &gt));
    // where the answer puts the survey's centre (the translation alone carries the lever of the
    // map's origin, 1.7e6 away)
    let moved = |m: &nalgebra::Matrix4<f64>| m.transform_point(&nalgebra::Point3::from(c));
    let off = (moved(t) - moved(&gt)).norm();
    let half = source.half_extent();
    assert!(off < 1e-3 * half, "the survey's centre off by {off} (half extent {half})");
}

fn set(b: &mut [u8], at: usize, v: &[u8]) {
    b[at..at + v.len()].copy_from_slice(v);
}

#[test]
fn hostile_headers_give_errors_that_say_what() {
    let las = fixture("simple.las");
    has(&err(&las[..100], "a.las"), &["LAS", "fewer than a LAS header's 227"]);
    has(&err(b"LASX and more", "a.las"), &["'LASF' signature"]);
    let mut b = las.clone();
    b[24] = 2;
    has(&err(&b, "a.las"), &["version 2.2 is not supported"]);
    let mut b = las.clone();
    b[104] = 11;
    has(&err(&b, "a.las"), &["point data format 11"]);
    let mut b = las.clone();
    set(&mut b, 105, &20u16.to_le_bytes());
    has(&err(&b, "a.las"), &["20 bytes are shorter than point data format 3's 34"]);
    let mut b = las.clone();
    set(&mut b, 96, &u32::MAX.to_le_bytes());
    has(&err(&b, "a.las"), &["offset to the point data"]);
    let mut b = las.clone();
    set(&mut b, 131, &0f64.to_le_bytes());
    has(&err(&b, "a.las"), &["x scale 0"]);
    let mut b = las.clone();
    set(&mut b, 171, &f64::NAN.to_le_bytes());
    has(&err(&b, "a.las"), &["z scale", "offset NaN"]);
    // more points claimed than the bytes hold: an error, not a short read
    let mut b = las.clone();
    set(&mut b, 107, &1066u32.to_le_bytes());
    has(&err(&b, "a.las"), &["claims 1066 points", "holds 1065"]);
    has(&err(&las[..las.len() - 10], "a.las"), &["claims 1065 points", "holds 1064"]);
    // a count beyond the readers' limit is refused before anything is read
    let mut b = las.clone();
    set(&mut b, 107, &u32::MAX.to_le_bytes());
    has(&err(&b, "a.las"), &["4294967295 points, more than"]);
    let mut b = las.clone();
    set(&mut b, 107, &0u32.to_le_bytes());
    has(&err(&b, "a.las"), &["no points"]);
}

/// The byte where `bytes`' point data starts (the header's offset).
fn data_start(bytes: &[u8]) -> usize {
    u32::from_le_bytes(bytes[96..100].try_into().unwrap()) as usize
}

#[test]
fn hostile_compressed_data_gives_errors_not_allocations() {
    let laz = fixture("simple.laz");
    let start = data_start(&laz);
    // the LASzip record's user id changed: no record to decompress with
    let mut b = laz.clone();
    let user = b.windows(14).position(|w| w == b"laszip encoded").unwrap();
    b[user] = b'L';
    has(&err(&b, "a.laz"), &["no LASzip record"]);
    // the compressor says layered, the items (point format 3, version 2) are not; and a layered
    // file (format 6) whose compressor says point-wise: the layer sizes would go unchecked
    let data = user - 2 + 54;
    let mut b = laz.clone();
    set(&mut b, data, &3u16.to_le_bytes());
    has(&err(&b, "a.laz"), &["compressor (3) and its items' version (2) disagree"]);
    let layered = fixture("1_4_w_evlr.laz");
    let at = layered.windows(14).position(|w| w == b"laszip encoded").unwrap() - 2 + 54;
    for compressor in [1u16, 2] {
        let mut b = layered.clone();
        set(&mut b, at, &compressor.to_le_bytes());
        has(&err(&b, "a.laz"), &[&format!("compressor ({compressor}) and its items' version (3) disagree")]);
    }
    // an item that says another size than the crate decodes (it slices each point by its own)
    let mut b = laz.clone();
    set(&mut b, data + 34 + 2, &5u16.to_le_bytes());
    has(&err(&b, "a.laz"), &["Point10 item says 5 bytes, not its 20"]);
    // the first variable length record's length runs past the point data
    let header_size = u16::from_le_bytes(laz[94..96].try_into().unwrap()) as usize;
    let mut b = laz.clone();
    set(&mut b, header_size + 20, &60000u16.to_le_bytes());
    has(
        &err(&b, "a.laz"),
        &["variable length record 1 of", "(60000 bytes from byte", "runs past the start of the point data"],
    );
    // a chunk table claiming four billion chunks: refused before the decompressor reserves them
    let table = i64::from_le_bytes(laz[start..start + 8].try_into().unwrap()) as usize;
    let mut b = laz.clone();
    set(&mut b, table + 4, &u32::MAX.to_le_bytes());
    has(&err(&b, "a.laz"), &["lists 4294967295 chunks"]);
    // a chunk table that points beyond the file
    let mut b = laz.clone();
    set(&mut b, start, &(laz.len() as i64 + 100).to_le_bytes());
    set(&mut b, laz.len() - 8, &(-1i64).to_le_bytes());
    let _ = read_point_cloud(&b, "a.laz"); // fixed-size chunks read without their table, or fail: no panic
                                           // the stream cut short: an error naming how far it got
    let cut = &laz[..start + (laz.len() - start) / 2];
    has(&err(cut, "a.laz"), &["LAS"]);
    // a layered file (point format 6) whose first chunk's XY layer claims 4 GB
    let laz = fixture("1_4_w_evlr.laz");
    let start = data_start(&laz);
    let record = u16::from_le_bytes(laz[105..107].try_into().unwrap()) as usize;
    let sizes = start + 8 + record + 4;
    let mut b = laz.clone();
    set(&mut b, sizes, &u32::MAX.to_le_bytes());
    has(&err(&b, "a.laz"), &["chunk 1 of 1", "layers", "overrun"]);
    // more points claimed than the chunk table's chunks hold
    let mut b = laz.clone();
    set(&mut b, 247, &2000u64.to_le_bytes());
    has(&err(&b, "a.laz"), &["end or break after 1000 of 2000 points"]);
    // and in a file of variable-size chunks, where the table counts each chunk's points
    let copc = fixture("simple.copc.laz");
    let mut b = copc.clone();
    set(&mut b, 247, &2000u64.to_le_bytes());
    has(&err(&b, "a.laz"), &["claims 2000 points", "hold 1065"]);
    // every prefix of both files: an error or the points, never a panic
    for name in ["simple.laz", "1_4_w_evlr.laz", "simple.copc.laz"] {
        let laz = fixture(name);
        for end in (0..laz.len()).step_by(97) {
            let _ = read_point_cloud(&laz[..end], name);
        }
    }
}

/// `ReadOptions::classes`: the points of the named classification codes alone, from LAS and LAZ
/// alike (point format 3, and format 6 whose layered chunks decode the classification layer only
/// when asked); counts as the files' classification bytes give them (`simple`: 789 of class 1,
/// 276 of class 2; `1_4_w_evlr`: 1000 of class 2).
#[test]
fn classes_keep_the_points_of_those_classification_codes() {
    use arps::io::{read_point_cloud_with, Classes, ReadOptions};
    let with = |name: &str, codes: &[u8]| {
        let options = ReadOptions { classes: Some(Classes::of(codes.iter().copied())), ..ReadOptions::default() };
        read_point_cloud_with(&fixture(name), name, &options)
    };
    let key = |c: &PointCloud| {
        let mut v: Vec<[i64; 3]> = (0..c.len()).map(|i| c.point_f64(i).map(|x| (x * 100.0).round() as i64)).collect();
        v.sort_unstable();
        v
    };
    for name in ["simple.las", "simple.laz", "simple.copc.laz"] {
        let (ground, other, both) =
            (with(name, &[2]).unwrap(), with(name, &[1]).unwrap(), with(name, &[1, 2]).unwrap());
        assert_eq!((ground.len(), other.len(), both.len()), (276, 789, 1065), "{name}");
        // the two classes split the file's points
        let mut split = key(&ground);
        split.extend(key(&other));
        split.sort_unstable();
        assert_eq!(split, key(&read(name)), "{name}");
    }
    assert_eq!(with("simple.laz", &[2]).unwrap(), with("simple.las", &[2]).unwrap());
    for name in ["1_4_w_evlr.las", "1_4_w_evlr.laz"] {
        assert_eq!(with(name, &[2]).unwrap(), read(name), "{name}");
        let e = with(name, &[6, 9]).unwrap_err().to_string();
        has(&e, &["none of its 1000 points is of classes 6, 9", "it holds classes 2 (1000)"]);
    }
    // a format without classifications
    let e = with("fuze_binary.ply", &[2]).unwrap_err().to_string();
    has(&e, &["classes option", "PLY file", "only LAS and LAZ"]);
}
