//! E57 (ASTM E2807, what terrestrial and handheld laser scanners export): every point cloud of the
//! file (or one, [`super::ReadOptions::scan`]), each placed by its pose, as one cloud in the
//! file's frame, in `f64`. Spherical
//! coordinates (range, azimuth, elevation) are converted to Cartesian ones; points the scanner
//! marked invalid (no return, or a direction without a range) are left out. The file is read by
//! the `e57` crate, which checks its pages' checksums.

use super::util::bounded_capacity;
use crate::{Error, Result};
use e57::{CartesianCoordinate, E57Reader};
use std::io::Cursor;

const FORMAT: &str = "E57";

fn err(what: &str, e: e57::Error) -> Error {
    Error::parse(FORMAT, format!("{what}: {e}"))
}

/// The file opened by the e57 crate (its header and XML section read and checked). One function
/// for the readers and the mover, not inlined: the crate's reader is large in WebAssembly.
#[inline(never)]
pub(super) fn open(bytes: &[u8]) -> Result<E57Reader<Cursor<&[u8]>>> {
    E57Reader::new(Cursor::new(bytes)).map_err(|e| err("the file cannot be read", e))
}

/// The point clouds (scans) an E57 file holds, in the file's order: each one's name and record
/// count (invalid points included), read from the file's XML section alone.
pub(crate) fn scans(bytes: &[u8]) -> Result<Vec<super::ScanInfo>> {
    let reader = open(bytes)?;
    Ok(reader.pointclouds().into_iter().map(|c| super::ScanInfo { name: c.name, records: c.records }).collect())
}

/// Reads the points of every point cloud of an E57 file, or of the one numbered `scan`
/// (0-based), in the file's frame.
pub(crate) fn read(bytes: &[u8], scan: Option<usize>) -> Result<Vec<[f64; 3]>> {
    let mut reader = open(bytes)?;
    let clouds = reader.pointclouds();
    let n = clouds.len();
    if n == 0 {
        return Err(Error::parse(FORMAT, "the file holds no point clouds (its data3D list is empty)"));
    }
    let chosen: Vec<(usize, &e57::PointCloud)> = match scan {
        Some(k) if k >= n => {
            return Err(Error::InvalidOption(format!("scan = {k}, but the E57 file holds {n} scans (0 to {})", n - 1)))
        }
        Some(k) => vec![(k, &clouds[k])],
        None => clouds.iter().enumerate().collect(),
    };
    let records = chosen.iter().fold(0u64, |sum, (_, c)| sum.saturating_add(c.records));
    crate::limits::check_file_points(FORMAT, records)?;
    // a record can take under a byte (bit-packed integers): the reservation is bounded, the rest grows
    let mut points = Vec::with_capacity(bounded_capacity(records, bytes.len(), 4));
    for (k, cloud) in chosen {
        let what = || format!("point cloud {} of {n}", k + 1);
        let mut iter = reader.pointcloud_simple(cloud).map_err(|e| err(&what(), e))?;
        // only the coordinates are used: no colour from intensity, no normalising
        iter.intensity_to_color(false);
        iter.normalize_intensity(false);
        iter.normalize_color(false);
        for p in iter {
            let p = p.map_err(|e| err(&what(), e))?;
            if let CartesianCoordinate::Valid { x, y, z } = p.cartesian {
                points.push([x, y, z]);
            }
        }
    }
    Ok(points)
}
