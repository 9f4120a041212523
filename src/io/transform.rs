//! A file moved as it is, whatever its format: the mover of the format the file is in
//! ([`transform_ply`](super::transform_ply), [`transform_las`](super::transform_las),
//! [`transform_pcd`](super::transform_pcd), [`transform_text`](super::transform_text), and those
//! of OBJ, OFF, STL, E57 and glTF), so that a registered scan can be saved in the target's frame in its own
//! format, with everything the registration did not read (colours, intensity, normals, faces,
//! other fields).

use super::{detect_format, Format, ReadOptions};
use crate::Result;
use nalgebra::Matrix4;

/// True when a file of this name is one [`transform_file`] moves as it is: PLY, PCD, text point
/// lists (XYZ, PTS, TXT, CSV), OBJ, OFF, STL, LAS, LAZ, E57 and glTF (GLB) by their
/// extension (case-insensitive): every format the readers know ([`Format::from_file_name`]).
/// False for unknown extensions: save such a source's points
/// moved instead ([`super::write_ply_binary`] of
/// [`PointCloud::transformed`](crate::PointCloud::transformed)).
pub fn can_transform(file_name: &str) -> bool {
    Format::from_file_name(file_name).is_some()
}

/// The file `bytes` (named `file_name`, whose extension, or else whose content, says the format:
/// [`detect_format`]) in its own format with its points moved by `m` (`T_target_source`: a rigid
/// transform, or one times a uniform scale for a change of unit) and its normals turned,
/// everything else kept as it was: see each format's mover for what that means. A LAZ file comes
/// back as LAZ, its points compressed again; an E57 file keeps its points as
/// stored and gets new poses (rigid motions only); a glTF file gets the motion as a new parent of
/// its top nodes, its buffers unchanged. Errors: a file its reader
/// refuses, coordinates stored as integers where the moved ones cannot be stored, a transform
/// that is not rigid (or uniformly scaled).
pub fn transform_file(bytes: &[u8], file_name: &str, m: &Matrix4<f64>) -> Result<Vec<u8>> {
    transform_file_with(bytes, file_name, m, &ReadOptions::default())
}

/// [`transform_file`] for the cloud that [`read_point_cloud_with`](super::read_point_cloud_with)
/// reads with `options`: with [`ReadOptions::scan`] set, an E57 file's scan alone, as an E57
/// file of its own (its points' and images' pages copied as they are, the XML listing only them,
/// their poses moved; an error for a scan beyond the file's, or set for a file of another
/// format); every other file as
/// [`transform_file`] moves it (a mesh read as points over its surface is moved as the mesh, a
/// LAS file read with [`ReadOptions::classes`] is moved whole: every point, whatever its class).
pub fn transform_file_with(bytes: &[u8], file_name: &str, m: &Matrix4<f64>, options: &ReadOptions) -> Result<Vec<u8>> {
    // a text file's UTF-8 byte order mark: read past, and written back in front
    let (bytes, bom) = super::after_bom(bytes)?;
    let moved = transform_format(bytes, file_name, m, options)?;
    Ok(if bom.is_empty() { moved } else { [bom, &moved[..]].concat() })
}

/// [`transform_file_with`] of a file without a byte order mark.
fn transform_format(bytes: &[u8], file_name: &str, m: &Matrix4<f64>, options: &ReadOptions) -> Result<Vec<u8>> {
    let format = detect_format(bytes, file_name)?;
    super::check_scan(format, options.scan)?;
    match format {
        Format::Ply => super::transform_ply(bytes, m),
        Format::Pcd => super::transform_pcd(bytes, m),
        Format::Xyz => super::transform_text(bytes, m),
        Format::Obj => super::obj_transform::transform_obj(bytes, m),
        Format::Stl => super::stl_transform::transform_stl(bytes, m),
        Format::Las => super::transform_las(bytes, m),
        Format::E57 => match options.scan {
            Some(scan) => super::e57_transform::transform_e57_scan(bytes, scan, m),
            None => super::e57_transform::transform_e57(bytes, m),
        },
        Format::Off => super::off_transform::transform_off(bytes, m),
        Format::Gltf => super::gltf_transform::transform_gltf(bytes, m),
    }
}
