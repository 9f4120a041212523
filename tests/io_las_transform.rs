//! `io::transform_las`: a LAS file moved as it is. On the laspy fixtures (LAS 1.2 format 3 with
//! colour and GPS time; LAS 1.4 format 6 with EVLRs after the points): the points read back are
//! the transform of the file's own to the file's scale; every record's other bytes, the VLRs and
//! EVLRs are kept; the header's offsets and bounds say where the points now are. A LAZ file comes
//! back as LAZ, its records decompressing to what the LAS fixture gives, byte for byte. A motion
//! the scales cannot store, a transform that is not rigid and every truncation are refused.

use arps::io::{read_point_cloud, transform_las};
use nalgebra::{Matrix4, Rotation3, Vector3};

fn fixture(name: &str) -> Vec<u8> {
    std::fs::read(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/formats").join(name)).unwrap()
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

fn f64_at(b: &[u8], at: usize) -> f64 {
    f64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}

/// 30 degrees about the vertical through a point of the survey, then a shift: a registration's
/// answer between two visits.
fn motion(about: [f64; 3]) -> Matrix4<f64> {
    let c = Vector3::from(about);
    Matrix4::new_translation(&(c + Vector3::new(12.5, -7.25, 1.5)))
        * Rotation3::from_axis_angle(&Vector3::z_axis(), 30f64.to_radians()).to_homogeneous()
        * Matrix4::new_translation(&-c)
}

/// Checks `moved` against `bytes` moved by `m`: the scales times `m`'s uniform scale (a change
/// of unit keeps the points' precision), points to within half a scale step (plus the reader's
/// f32 offsets), every record's bytes after X, Y, Z and everything after the records kept, the
/// header's bounds those of the points.
fn check(bytes: &[u8], moved: &[u8], m: &Matrix4<f64>) {
    assert_eq!(moved.len(), bytes.len());
    let (offset, record, count) = records(bytes);
    let factor = m.fixed_view::<3, 3>(0, 0).determinant().cbrt();
    let scale = [131, 139, 147].map(|at| f64_at(moved, at));
    for (k, at) in [131, 139, 147].into_iter().enumerate() {
        let want = f64_at(bytes, at) * factor;
        assert!((scale[k] - want).abs() <= 1e-11 * want, "axis {k}'s scale {} for {want}", scale[k]);
    }
    assert!(moved[..131] == bytes[..131], "the header before the scales");
    assert!(moved[227..offset] == bytes[227..offset], "the rest of the header and the VLRs");
    let end = offset + count * record;
    assert!(moved[end..] == bytes[end..], "what follows the points (EVLRs)");
    for i in 0..count {
        let at = offset + i * record;
        assert!(moved[at + 12..at + record] == bytes[at + 12..at + record], "record {i}'s attributes");
    }
    let (before, after) = (read_point_cloud(bytes, "a.las").unwrap(), read_point_cloud(moved, "a.las").unwrap());
    assert_eq!(after.len(), count);
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for i in 0..count {
        let want = m.transform_point(&nalgebra::Point3::from(before.point_f64(i)));
        let got = after.point_f64(i);
        for k in 0..3 {
            // half a scale step, plus the reader's f32 offsets (both clouds go through them)
            assert!((got[k] - want[k]).abs() <= scale[k] / 2.0 + 2e-4, "point {i} axis {k}: {} vs {}", got[k], want[k]);
            lo[k] = lo[k].min(got[k]);
            hi[k] = hi[k].max(got[k]);
        }
    }
    for k in 0..3 {
        let (max, min) = (f64_at(moved, 179 + 16 * k), f64_at(moved, 187 + 16 * k));
        assert!(
            (max - hi[k]).abs() < 1e-3 && (min - lo[k]).abs() < 1e-3,
            "axis {k} bounds [{min}, {max}] vs [{}, {}]",
            lo[k],
            hi[k]
        );
    }
}

#[test]
fn a_las_1_2_survey_keeps_its_colours_and_gps_times() {
    let bytes = fixture("simple.las");
    let first = read_point_cloud(&bytes, "a.las").unwrap().point_f64(0);
    let m = motion(first);
    let moved = transform_las(&bytes, &m).unwrap();
    check(&bytes, &moved, &m);
    // a correction of metres keeps the file's offsets, as its tools wrote them (here not round)
    assert!(moved[155..179] == bytes[155..179], "the offsets kept");
    let mut shifted = bytes.clone();
    shifted[155..163].copy_from_slice(&123_456.78f64.to_le_bytes());
    let moved = transform_las(&shifted, &m).unwrap();
    check(&shifted, &moved, &m);
    assert_eq!(f64_at(&moved, 155), 123_456.78, "the offsets kept");
    // moved 30,000 km (3e9 steps of its scale 0.01 from its offsets), new ones: round, near the points
    let far = Matrix4::new_translation(&Vector3::new(3e7, 0.0, 0.0));
    let moved = transform_las(&bytes, &far).unwrap();
    check(&bytes, &moved, &far);
    let (offset_x, was) = (f64_at(&moved, 155), f64_at(&bytes, 155));
    assert!(offset_x != was && offset_x % 1e6 == 0.0 && (offset_x - was - 3e7).abs() < 1e7, "{was} -> {offset_x}");
    assert!(moved[163..179] == bytes[163..179], "y and z keep theirs");
}

#[test]
fn a_las_1_4_file_keeps_its_evlrs() {
    let bytes = fixture("1_4_w_evlr.las");
    let first = read_point_cloud(&bytes, "a.las").unwrap().point_f64(0);
    let m = motion(first);
    check(&bytes, &transform_las(&bytes, &m).unwrap(), &m);
    // a uniform scale (a change of unit) too: to a thousandth (millimetres to metres), the grid
    // scaled with the points (kept, the file's scales would store them a thousand times coarser)
    for factor in [1.5, 0.001] {
        let scaled = m * Matrix4::new_scaling(factor);
        check(&bytes, &transform_las(&bytes, &scaled).unwrap(), &scaled);
    }
}

/// The LASzip record's data and where it starts, found by its user id among the VLRs.
fn laszip_record(bytes: &[u8]) -> (Vec<u8>, usize) {
    let at = bytes.windows(14).position(|w| w == b"laszip encoded").unwrap() - 2;
    let len = u16::from_le_bytes([bytes[at + 20], bytes[at + 21]]) as usize;
    (bytes[at + 54..at + 54 + len].to_vec(), at)
}

/// Where a LAS file's point records start, their size and count.
fn records(bytes: &[u8]) -> (usize, usize, usize) {
    let (offset, record) = (u32_at(bytes, 96) as usize, u16::from_le_bytes([bytes[105], bytes[106]]) as usize);
    // LAS 1.4 keeps the count in 64 bits (the legacy 32-bit field may be 0)
    let legacy = u32_at(bytes, 107) as usize;
    (offset, record, if legacy > 0 { legacy } else { u64::from_le_bytes(bytes[247..255].try_into().unwrap()) as usize })
}

/// The point records of a LAZ file, decompressed by the `laz` crate.
fn laz_records(bytes: &[u8]) -> Vec<u8> {
    let (offset, record, count) = records(bytes);
    let vlr = laz::LazVlr::from_buffer(laszip_record(bytes).0).unwrap();
    let mut cursor = std::io::Cursor::new(bytes);
    cursor.set_position(offset as u64);
    let mut decompressor = laz::LasZipDecompressor::new(cursor, vlr).unwrap();
    let mut out = vec![0u8; count * record];
    decompressor.decompress_many(&mut out).unwrap();
    out
}

/// Where a LAS 1.4 file's extended VLRs start.
fn evlrs_at(bytes: &[u8]) -> usize {
    u64::from_le_bytes(bytes[235..243].try_into().unwrap()) as usize
}

#[test]
fn a_laz_file_comes_back_as_laz_whose_points_are_the_las_files_moved() {
    // the LAZ fixtures compress the LAS ones (LAS 1.2 format 3, point-wise chunks; LAS 1.4 format
    // 6, layered chunks, with EVLRs after the points): moved, they decompress to the LAS ones
    // moved, to the byte, and keep their header and VLRs but the points' offsets and bounds
    let m = motion([0.0; 3]) * Matrix4::new_scaling(1.5);
    for (laz, las) in [("simple.laz", "simple.las"), ("1_4_w_evlr.laz", "1_4_w_evlr.las")] {
        let (laz_bytes, las_bytes) = (fixture(laz), fixture(las));
        let moved = transform_las(&laz_bytes, &m).unwrap();
        let moved_las = transform_las(&las_bytes, &m).unwrap();
        assert_eq!(moved[104] & 0x80, 0x80, "{laz}: the point format is marked compressed");
        assert!(moved.len() * 10 < moved_las.len() * 6, "{laz}: {} bytes, the LAS {}", moved.len(), moved_las.len());
        // unmoved, compressed as small as LASzip compressed it (moved, the points' deltas change)
        let same = transform_las(&laz_bytes, &Matrix4::identity()).unwrap().len();
        assert!(same * 100 < laz_bytes.len() * 102, "{laz}: {same} bytes unmoved, the LAZ {}", laz_bytes.len());
        let (offset, record, count) = records(&moved_las);
        assert!(laz_records(&moved) == moved_las[offset..offset + count * record], "{laz}: the records");
        let (a, b) = (read_point_cloud(&moved, "a.laz").unwrap(), read_point_cloud(&moved_las, "a.las").unwrap());
        assert!((0..a.len()).all(|i| a.point_f64(i) == b.point_f64(i)) && a.len() == b.len(), "{laz}: the points");
        assert!(moved[..96] == laz_bytes[..96] && moved[100..131] == laz_bytes[100..131], "{laz}: the header");
        assert!(moved[131..227] == moved_las[131..227], "{laz}: the moved points' scales, offsets and bounds");
        let (vlr_at, len_at) =
            (laszip_record(&laz_bytes).1, 227.max(u16::from_le_bytes([laz_bytes[94], laz_bytes[95]]) as usize));
        assert!(moved[len_at..vlr_at] == laz_bytes[len_at..vlr_at], "{laz}: the VLRs before the LASzip record");
        if laz_bytes[25] == 4 {
            assert!(moved[evlrs_at(&moved)..] == moved_las[evlrs_at(&moved_las)..], "{laz}: the EVLRs");
            assert!(moved[227..235] == laz_bytes[227..235] && moved[243..][..4] == laz_bytes[243..247]);
        }
    }
    // a COPC file (LAZ in chunks of varying size, an octree indexed by byte offsets): a plain LAZ
    // file, its COPC records left out, its points moved
    let copc = fixture("simple.copc.laz");
    let moved = transform_las(&copc, &m).unwrap();
    assert_eq!(moved[104] & 0x80, 0x80);
    assert!(copc.windows(5).any(|w| w == b"copc\0") && !moved.windows(5).any(|w| w == b"copc\0"), "COPC's records");
    assert_eq!(u32_at(&moved, 100), u32_at(&copc, 100) - 1, "the VLRs but COPC's");
    assert_eq!(u32_at(&moved, 243), u32_at(&copc, 243) - 1, "the EVLRs but COPC's");
    let (before, after) = (read_point_cloud(&copc, "a.laz").unwrap(), read_point_cloud(&moved, "a.laz").unwrap());
    assert_eq!(before.len(), after.len());
    assert_eq!(laz_records(&moved).len(), before.len() * u16::from_le_bytes([copc[105], copc[106]]) as usize);
    // (the moved file's scales: 1.5 times the file's)
    let scale = [131, 139, 147].map(|at| f64_at(&moved, at));
    assert!((0..3).all(|k| (scale[k] - 1.5 * f64_at(&copc, 131 + 8 * k)).abs() < 1e-12), "{scale:?}");
    for i in 0..before.len() {
        let want = m.transform_point(&nalgebra::Point3::from(before.point_f64(i)));
        let got = after.point_f64(i);
        assert!((0..3).all(|k| (got[k] - want[k]).abs() <= scale[k] / 2.0 + 2e-4), "point {i}: {got:?} vs {want:?}");
    }
}

#[test]
fn motions_the_scales_cannot_store_and_other_transforms_are_refused() {
    let m = motion([0.0; 3]);
    let bytes = fixture("simple.las");
    let mut sheared = m;
    sheared[(0, 2)] += 0.5;
    assert!(transform_las(&bytes, &sheared).unwrap_err().to_string().contains("not rigid"));
    assert!(transform_las(b"not a las file", &m).unwrap_err().to_string().contains("LASF"));
    // two points about 4.2e9 steps apart on a diagonal: turned 45 degrees they are 5.9e9 apart in
    // x, beyond 32-bit integers on either side of any offset
    let mut wide = bytes.clone();
    let (offset, record) = (u32_at(&bytes, 96) as usize, u16::from_le_bytes([bytes[105], bytes[106]]) as usize);
    for (i, (x, y)) in [(2_100_000_000i32, -2_100_000_000i32), (-2_100_000_000, 2_100_000_000)].into_iter().enumerate()
    {
        wide[offset + i * record..offset + i * record + 4].copy_from_slice(&x.to_le_bytes());
        wide[offset + i * record + 4..offset + i * record + 8].copy_from_slice(&y.to_le_bytes());
    }
    let turn = Rotation3::from_axis_angle(&Vector3::z_axis(), 45f64.to_radians()).to_homogeneous();
    let e = transform_las(&wide, &turn).unwrap_err().to_string();
    assert!(e.contains("more than the file's scale") && e.contains(" in x,"), "{e}");
    // every prefix: refused, never a panic (the points end the file's bytes that matter)
    for cut in (0..bytes.len()).step_by(53) {
        let end = offset + 1065 * record;
        match transform_las(&bytes[..cut], &m) {
            Ok(_) => assert!(cut >= end, "cut at {cut}"),
            Err(e) => assert!(!e.to_string().is_empty()),
        }
    }
}
