//! A text point list (XYZ, PTS, CSV, TXT) moved as it is: each data row's coordinates rewritten,
//! its normal turned, every other byte kept (the header, comments, other columns such as
//! intensity and colour, the separators, the line endings).
//!
//! The rows are the ones the reader reads ([`super::text`]), in the columns it reads. A normal is
//! turned when the header names its columns (`nx ny nz`, `normal_x ...`), or, in a list without
//! column names, when the three columns after x, y, z hold a unit vector on every row (MeshLab's
//! and CloudCompare's `x y z nx ny nz`); a header that names the columns and no normal has none
//! (its `r g b` may be colours from 0 to 1, every pure one a unit vector). Values are written
//! with as many decimals as the file's most precise coordinate (fewer or more after a change of
//! unit: see [`super::number_style::NumberStyle`]), or in exponent form when the file uses it;
//! normals with at least six decimals. Rows whose coordinates are not finite are kept as they are.

use super::motion::Motion;
use super::number_style::{span, Rewrite, Styles};
use super::text::{decimal_commas, scan, values, Row};
use super::util::show;
use crate::{Error, Result};
use nalgebra::{Matrix4, Vector3};

/// How far from 1 a normal's length may be (values rounded to a few decimals).
const UNIT_TOLERANCE: f64 = 1e-2;

/// Where an unnamed list's normal would be: the three columns after x, y, z.
const AFTER_XYZ: [usize; 3] = [3, 4, 5];

/// Where `row`'s normal is: the columns the header names, else, in a list without column names
/// and when `guess`, the three after x, y, z. A header that names its columns and no normal has
/// none: its `r g b` with colours from 0 to 1 (a pure red is a unit vector) are not turned.
fn normal_columns(row: &Row, guess: bool) -> Option<[usize; 3]> {
    row.columns.normal.or((guess && !row.columns.named).then_some(AFTER_XYZ))
}

/// The text list `bytes` with its points moved by `m` (`T_target_source`: a rigid transform, or
/// one times a uniform scale) and its normals turned, everything else as it was (see the module
/// docs). Errors: a file the reader refuses, a transform that is not rigid (or uniformly scaled).
pub fn transform_text(bytes: &[u8], m: &Matrix4<f64>) -> Result<Vec<u8>> {
    let motion = Motion::new(m)?;
    // First pass: how the file writes its numbers, and whether an unnamed list holds normals.
    let mut styles = Styles::default();
    let mut unit_after_xyz = true;
    scan(bytes, &mut |row| {
        for &c in &row.columns.xyz {
            styles.position.learn(row.fields[c]);
        }
        styles.bound(row.point);
        match normal_columns(row, true).and_then(|c| values(row.fields, c).map(|n| (c, n))) {
            Some((normal, n)) => {
                normal.iter().for_each(|&c| styles.normal.learn(row.fields[c]));
                unit_after_xyz &= (Vector3::from(n).norm() - 1.0).abs() <= UNIT_TOLERANCE;
            }
            None => unit_after_xyz = false,
        }
        Ok(())
    })?;
    let styles = styles.for_writing(&motion);
    // Second pass: the data rows rewritten, the bytes between them copied.
    let mut out = Rewrite::new(bytes);
    let mut edits = Vec::with_capacity(6);
    scan(bytes, &mut |row| {
        if !row.point.iter().all(|v| v.is_finite()) {
            return Ok(());
        }
        let normal = normal_columns(row, unit_after_xyz);
        let p = motion.point(row.point);
        edits.clear();
        edits.extend(row.columns.xyz.iter().zip(p).map(|(&c, v)| (span(row.line, row.fields[c]), v, styles.position)));
        if let Some(columns) = normal {
            if let Some(n) = values(row.fields, columns).filter(|n| n.iter().all(|v| v.is_finite())) {
                let n = motion.normal(n);
                edits.extend(columns.iter().zip(n).map(|(&c, v)| (span(row.line, row.fields[c]), v, styles.normal)));
            }
        }
        // A row whose rewritten values the reader would take for numbers with decimal commas
        // (`48 -50,34` from `1.5e0 0.,75`: values joined by a comma in a whitespace-separated
        // row) gets a decimal point in each; one still read so is refused.
        let readable = |l: &[u8]| !l.contains(&b',') || std::str::from_utf8(l).is_ok_and(|l| !decimal_commas(l));
        if !out.line_if(row.line, &mut edits, &readable) {
            edits.iter_mut().for_each(|e| e.2 = e.2.with_point());
            if !out.line_if(row.line, &mut edits, &readable) {
                return Err(Error::unmovable(
                    "XYZ",
                    format!("{}: its moved values would read as numbers with decimal commas", show(row.line.trim())),
                ));
            }
        }
        Ok(())
    })?;
    Ok(out.finish())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::text::read;

    #[test]
    fn values_joined_by_a_comma_in_a_spaced_row_stay_readable() {
        // (found by fuzzing) `0.,75` is y and z; moved, `-50,34` would read as one number with a
        // decimal comma
        let file = b"0.5 y.0 0.0 1.0\n1.5e0 0.,75 5e0 0.75 2.0 0.6 0.8 0.0\n";
        let turn = nalgebra::Rotation3::from_euler_angles(0.3, -1.1, 2.0).to_homogeneous();
        let m = Matrix4::new_translation(&Vector3::new(1.5, -2.0, 0.25)) * turn;
        let moved = transform_text(file, &m).unwrap();
        let (before, after) = (read(file).unwrap(), read(&moved).unwrap());
        assert_eq!(before.len(), after.len());
        let expected = m.transform_point(&before[0].into());
        // (written with the file's two significant digits)
        for k in 0..3 {
            assert!((after[0][k] - expected[k]).abs() < 0.5, "{:?} {expected}", after[0]);
        }
        assert!(String::from_utf8_lossy(&moved).contains(" -5.0e1,3.4e1 "), "{}", String::from_utf8_lossy(&moved));
        // comma-separated integers stay as they were written
        let moved = transform_text(b"1,2,3\n100000,0,0\n", &Matrix4::new_translation(&Vector3::new(12.0, 0.0, 0.0)));
        assert_eq!(String::from_utf8(moved.unwrap()).unwrap(), "13,2,3\n100012,0,0\n");
    }
}
