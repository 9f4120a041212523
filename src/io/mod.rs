//! Readers for point-cloud and mesh files, and a binary PLY writer.
//!
//! | format | extensions | variants |
//! | --- | --- | --- |
//! | [`Format::Ply`] | `.ply` | ascii, binary little/big endian; any vertex properties; faces |
//! | [`Format::Pcd`] | `.pcd` | DATA ascii, binary, binary_compressed (LZF); organised clouds |
//! | [`Format::Xyz`] | `.xyz .pts .txt .csv` | whitespace/comma/semicolon separated; the columns a header names (`x y z`, `Easting,Northing,Elevation`; two named without the third is an error), else the first three numbers |
//! | [`Format::Obj`] | `.obj` | `v` and `f` (`i`, `i/t`, `i//n`, `i/t/n`, negative indices) |
//! | [`Format::Off`] | `.off` | `OFF`, `COFF`, `NOFF`, `CNOFF`, `STOFF`, counts on the header line |
//! | [`Format::Stl`] | `.stl` | ascii and binary (also binary files whose header starts with `solid`) |
//! | [`Format::Las`] | `.las .laz` | LAS 1.0 to 1.4, point formats 0 to 10; LAZ (LASzip) compressed |
//! | [`Format::E57`] | `.e57` | every point cloud placed by its pose; Cartesian or spherical; invalid points left out |
//! | [`Format::Gltf`] | `.glb .gltf` | glTF 2.0: the default scene's meshes placed by their nodes, skins and morph targets applied; quantised, interleaved, sparse, GPU-instanced; buffers in the file (Draco or meshopt compressed only when it holds the data uncompressed too) |
//!
//! Readers are written for hostile input: malformed files give an [`Error::Parse`] saying what
//! and where (line number, byte offset, element name), never a panic, and no reservation is
//! sized by a header count beyond what the remaining bytes could hold. Points are read
//! faithfully (NaN stays NaN); [`PointCloud::validated`] is where they are checked.
//!
//! A mesh file gives its vertices ([`read_point_cloud`]), its triangles too ([`read_mesh`]), or
//! points drawn uniformly over its surface ([`read_point_cloud_with`], [`ReadOptions`]): a CAD
//! model's vertices sit on its edges and corners, so a scan registers against its surface.
//!
//! A registered source is saved in the target's frame as the file it was, moved
//! ([`transform_file`]: PLY, PCD, text lists, OBJ, OFF, STL, LAS, E57, glTF; everything else in the file kept), or
//! as its points ([`write_ply_binary`] of [`PointCloud::transformed`]).
//!
//! Coordinates are read as precisely as the file holds them (`double` properties and text in
//! `f64`), and a cloud far from zero gets an origin near its points before anything becomes `f32`
//! ([`PointCloud::from_points_f64`]), so map-grid coordinates (5e6) keep their shape.

use crate::cloud::PointCloud;
use crate::{Error, Result};

mod classes;
mod e57;
mod e57_transform;
mod gltf;
mod gltf_transform;
mod keyword_lines;
mod las;
mod las_transform;
mod laz_write;
mod lzf;
mod mesh;
mod motion;
mod number_style;
mod obj;
mod obj_transform;
mod off;
mod off_transform;
mod pcd;
mod pcd_transform;
mod ply;
mod ply_transform;
mod splat;
mod stl;
mod stl_transform;
mod text;
mod text_transform;
mod transform;
mod util;

/// A triangle mesh (vertices and triangles), as read from OBJ/OFF/STL/PLY/glTF.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub vertices: Vec<[f32; 3]>,
    /// Triangles as vertex indices (polygons are fan-triangulated).
    pub triangles: Vec<[u32; 3]>,
}

/// What a PLY reader does with a `face` element (the other mesh formats are parsed whole).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Faces {
    /// Stop after the vertices.
    Skip,
    /// Read the faces; a file without them is an error.
    Required,
    /// Read the faces when the file has them.
    IfAny,
}

/// What a reader returns: vertices in `f64` (as precise as the file), and triangles.
pub(crate) struct Raw {
    vertices: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
}

impl Raw {
    /// The vertices as a cloud, large coordinates keeping their shape
    /// ([`PointCloud::from_points_f64`]).
    fn into_cloud(self) -> PointCloud {
        PointCloud::from_points_f64(&self.vertices)
    }

    /// As a [`Mesh`] (vertices rounded to `f32`).
    fn into_mesh(self) -> Mesh {
        Mesh { vertices: self.vertices.iter().map(|p| p.map(|v| v as f32)).collect(), triangles: self.triangles }
    }
}

/// A file format the readers understand.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Format {
    /// Stanford PLY.
    Ply,
    /// PCL's Point Cloud Data.
    Pcd,
    /// Text point lists (XYZ, PTS, CSV, TXT).
    Xyz,
    /// Wavefront OBJ.
    Obj,
    /// Object File Format.
    Off,
    /// Stereolithography.
    Stl,
    /// ASPRS LAS, and LAS compressed by LASzip (LAZ): airborne and terrestrial LiDAR, survey data.
    Las,
    /// ASTM E57, the exchange format of terrestrial and handheld laser scanners.
    E57,
    /// glTF 2.0, binary (`.glb`) or JSON (`.gltf`): the web's 3D scene format, exported by
    /// phone-capture apps and CAD viewers. Y-up, in metres.
    Gltf,
}

impl Format {
    /// The format's name as used in error messages (`"PLY"`, `"PCD"`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Format::Ply => "PLY",
            Format::Pcd => "PCD",
            Format::Xyz => "XYZ",
            Format::Obj => "OBJ",
            Format::Off => "OFF",
            Format::Stl => "STL",
            Format::Las => "LAS",
            Format::E57 => "E57",
            Format::Gltf => "glTF",
        }
    }

    /// The format for a file name's extension (case-insensitive), if it is a known one.
    pub fn from_file_name(file_name: &str) -> Option<Format> {
        let (_, ext) = file_name.rsplit_once('.')?;
        Some(match ext.to_ascii_lowercase().as_str() {
            "ply" => Format::Ply,
            "pcd" => Format::Pcd,
            "xyz" | "pts" | "txt" | "csv" => Format::Xyz,
            "obj" => Format::Obj,
            "off" => Format::Off,
            "stl" => Format::Stl,
            "las" | "laz" => Format::Las,
            "e57" => Format::E57,
            "glb" | "gltf" => Format::Gltf,
            _ => return None,
        })
    }

    /// True for formats that carry faces (OBJ, OFF, STL, PLY, glTF).
    pub fn has_faces(self) -> bool {
        !matches!(self, Format::Pcd | Format::Xyz | Format::Las | Format::E57)
    }
}

/// Tells the format of a file: by its signature when it starts with one (`ply` magic; `LASF`,
/// `ASTM-E57` and `glTF` signatures; PCD's `# .PCD` comment; an `OFF` header), whatever its name says, so that a file
/// saved under another format's extension (a PLY file named `.txt`) is still read as what it is;
/// else from the file name's extension (`.ply .pcd .xyz .pts .txt .csv .obj .off .stl .las .laz
/// .e57 .glb .gltf`, case-insensitive) when it has a known one; else sniffed from the content (the
/// signatures; a glTF JSON object; a PCD `VERSION` / `FIELDS` line; binary STL by its size rule or
/// `solid ... facet`; OBJ `v` lines; else rows of numbers).
pub fn detect_format(bytes: &[u8], file_name: &str) -> Result<Format> {
    if let Some(f) = signature(bytes) {
        return Ok(f);
    }
    if let Some(f) = Format::from_file_name(file_name) {
        return Ok(f);
    }
    sniff(bytes).ok_or_else(|| {
        const KNOWN: &str = "and the content does not look like PLY, LAS, E57, glTF, PCD, OFF, STL, OBJ or a text list of points";
        let message = if file_name.is_empty() {
            format!(
                "cannot tell the format: no file name was given (pass the file's name, e.g. \"scan.ply\", \
                 so that its extension names the format), {KNOWN}"
            )
        } else {
            format!(
                "cannot tell the format of '{}': the extension is not one of .ply .pcd .xyz .pts .txt .csv .obj .off .stl .las .laz .e57 .glb .gltf, {KNOWN}",
                file_name.chars().take(200).collect::<String>()
            )
        };
        Error::parse("input", message)
    })
}

/// The format a file's first bytes name beyond doubt: PLY's `ply` line, LAS's `LASF`, E57's
/// `ASTM-E57`, glTF's `glTF`, PCD's `# .PCD` comment line, OFF's header keyword (`OFF`, `COFF`, ...) as its
/// first word. No file of another format starts so.
fn signature(bytes: &[u8]) -> Option<Format> {
    let first = bytes.split(|&b| b == b'\n').next().unwrap_or_default().trim_ascii();
    if first == b"ply" {
        return Some(Format::Ply);
    }
    if bytes.starts_with(b"LASF") {
        return Some(Format::Las);
    }
    if bytes.starts_with(b"ASTM-E57") {
        return Some(Format::E57);
    }
    if gltf::is_glb(bytes) {
        return Some(Format::Gltf);
    }
    if first.starts_with(b"# .PCD") {
        return Some(Format::Pcd);
    }
    if off::sniff(bytes) {
        return Some(Format::Off);
    }
    None
}

/// The format of a file without a [`signature`] nor a known extension, from its content
/// ([`detect_format`] has looked for the signatures already).
fn sniff(bytes: &[u8]) -> Option<Format> {
    if gltf::sniff_json(bytes) {
        return Some(Format::Gltf);
    }
    // PCD: a "# .PCD" comment or a VERSION / FIELDS line before anything else.
    for line in bytes[..bytes.len().min(4096)].split(|&b| b == b'\n').take(20) {
        let l = line.trim_ascii();
        if l.starts_with(b"# .PCD") {
            return Some(Format::Pcd);
        }
        if l.is_empty() || l.starts_with(b"#") {
            continue;
        }
        if l.starts_with(b"VERSION") || l.starts_with(b"FIELDS") {
            return Some(Format::Pcd);
        }
        break;
    }
    if stl::sniff(bytes) {
        return Some(Format::Stl);
    }
    if obj::sniff(bytes) {
        return Some(Format::Obj);
    }
    if text::sniff(bytes) {
        return Some(Format::Xyz);
    }
    None
}

fn read_format(
    bytes: &[u8],
    format: Format,
    faces: Faces,
    scan: Option<usize>,
    classes: Option<Classes>,
) -> Result<Raw> {
    match format {
        Format::Ply => ply::read(bytes, faces),
        Format::Pcd => pcd::read(bytes),
        Format::Xyz => text::read(bytes).map(|vertices| Raw { vertices, triangles: Vec::new() }),
        Format::Obj => obj::read(bytes),
        Format::Off => off::read(bytes),
        Format::Stl => stl::read(bytes),
        Format::Las => las::read(bytes, classes).map(|vertices| Raw { vertices, triangles: Vec::new() }),
        Format::E57 => e57::read(bytes, scan).map(|vertices| Raw { vertices, triangles: Vec::new() }),
        Format::Gltf => gltf::read(bytes, faces),
    }
}

/// Reads a point cloud from a file's bytes; the format comes from the file's signature, else
/// its name's extension, else it is sniffed from the content (see [`detect_format`]). Mesh formats give their
/// vertices (STL corners merged by position); OBJ, OFF and STL files are parsed whole, so a bad
/// face is an error here too, while a PLY file is read only up to its `vertex` element.
/// Non-finite coordinates are kept as they are. A text file may start with a UTF-8 byte order
/// mark; one in UTF-16 is refused by name. [`read_point_cloud_with`] can sample a mesh's
/// surface instead.
pub fn read_point_cloud(bytes: &[u8], file_name: &str) -> Result<PointCloud> {
    read_point_cloud_with(bytes, file_name, &ReadOptions::default())
}

/// How [`read_point_cloud_with`] turns a file into points. In JS (`parsePointCloud`,
/// `readPointCloud`) a plain object with these fields in camelCase, each optional.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "camelCase", default, deny_unknown_fields)]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "ReadOptions"))]
pub struct ReadOptions {
    /// For a file with faces (OBJ, OFF, STL, glTF/GLB, PLY with a `face` element): this many points drawn
    /// uniformly over its surface instead of its vertices. A CAD model's vertices sit on its
    /// edges and corners, and its flat faces have none, so a scan registers against its surface,
    /// not its vertices. From 16 to 16,000,000; files without faces are read as they are. Unset
    /// (the default): the vertices.
    #[cfg_attr(feature = "ts", ts(optional = nullable))]
    pub surface_points: Option<usize>,
    /// Seed of the surface sampling: the same file, count and seed give the same points on every
    /// platform. Default 0. A non-negative integer (in JS a `bigint` from 2^53 on: a number that large may have been rounded).
    #[cfg_attr(feature = "ts", ts(type = "number | bigint", optional = nullable))]
    pub seed: u64,
    /// For an E57 file, which holds one point cloud per scan: only this one (0-based, in the
    /// file's order), placed by its pose. An index beyond the file's scans is an error, and so is
    /// setting it for a file of another format (one cloud, nothing to choose: [`list_scans`] gives
    /// an empty list). Unset (the default): every scan, as one cloud.
    #[cfg_attr(feature = "ts", ts(optional = nullable))]
    pub scan: Option<usize>,
    /// For a LAS or LAZ file: only the points of these classification codes (ASPRS: 2 ground,
    /// 3-5 vegetation, 6 building, 7 low noise, 9 water, 18 high noise, ...), e.g. `[2]` to
    /// register two epochs by their ground where vegetation or buildings changed, or every code
    /// but the noise ones. An error when no point of the file is of them (the message names the
    /// classes it holds), when the list is empty, and for a file of another format (it has no
    /// classes). `transform_file` moves every point of the file whatever this says. Unset (the
    /// default): every point.
    #[cfg_attr(feature = "ts", ts(type = "number[]", optional = nullable))]
    pub classes: Option<Classes>,
    /// For a Gaussian splat PLY (a vertex `opacity` property, the logit the splat file stores):
    /// only the splats at least this opaque (the logit's sigmoid, in [0, 1]; 0.5 keeps those
    /// with a logit of 0 or more). Splat scenes hold transparent floaters strewn about and huge
    /// background splats that can mislead the search; their surfaces are the opaque splats. An
    /// error when no splat is that opaque, for a PLY without `opacity`, with `surfacePoints`, and
    /// for a file of another format. `transform_file` moves every splat of the file whatever
    /// this says. Unset (the default): every splat.
    #[cfg_attr(feature = "ts", ts(optional = nullable))]
    pub min_opacity: Option<f64>,
}

/// One scan of a file that holds several (E57), as [`list_scans`] describes it. In JS a plain
/// object with these fields.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "camelCase")]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "ScanInfo"))]
pub struct ScanInfo {
    /// The scan's name in the file, if it has one (often the scanner's station name).
    pub name: Option<String>,
    /// The scan's point records, invalid ones (no return) included: an upper bound of the points
    /// read. A non-negative integer (in JS a `number`).
    #[cfg_attr(feature = "ts", ts(type = "number"))]
    pub records: u64,
}

/// The scans of a file that holds several, in the file's order, so that one can be chosen
/// ([`ReadOptions::scan`]): for an E57 file its point clouds (from its XML section alone, no
/// point decoded); for any other format an empty list (one cloud, nothing to choose). Errors:
/// an E57 file that cannot be read, a name and content whose format cannot be told.
pub fn list_scans(bytes: &[u8], file_name: &str) -> Result<Vec<ScanInfo>> {
    let (bytes, _) = after_bom(bytes)?;
    match detect_format(bytes, file_name)? {
        Format::E57 => e57::scans(bytes),
        _ => Ok(Vec::new()),
    }
}

/// The file's bytes after a UTF-8 byte order mark, if it starts with one (Excel's and Notepad's
/// "CSV UTF-8" do), and that mark; an error for a file that starts with a UTF-16 one (a
/// PowerShell or Windows "Unicode" export), which no reader reads. No format's own first bytes
/// are these.
pub(crate) fn after_bom(bytes: &[u8]) -> Result<(&[u8], &[u8])> {
    const UTF8: &[u8] = b"\xEF\xBB\xBF";
    if let Some(rest) = bytes.strip_prefix(UTF8) {
        return Ok((rest, UTF8));
    }
    if bytes.starts_with(b"\xFF\xFE") || bytes.starts_with(b"\xFE\xFF") {
        return Err(Error::parse(
            "input",
            "the file is UTF-16 text (it starts with a UTF-16 byte order mark): save it as UTF-8 or ASCII text",
        ));
    }
    Ok((bytes, &[]))
}

/// Refuses [`ReadOptions::scan`] for a file of one cloud (every format but E57), where it
/// would choose nothing: a caller who sets it expects one scan of several.
pub(crate) fn check_scan(format: Format, scan: Option<usize>) -> Result<()> {
    match scan {
        Some(k) if format != Format::E57 => Err(Error::InvalidOption(format!(
            "the scan option ({k}) chooses among an E57 file's scans; a {} file holds one cloud: leave it unset",
            format.name()
        ))),
        _ => Ok(()),
    }
}

/// [`read_point_cloud`], with a mesh's surface sampled when `options.surface_points` is set
/// ([`ReadOptions`]): the points are drawn in `f64` from the file's own vertices, so large
/// coordinates keep their shape as the vertices do. Fails with a clear error for a count out of
/// range, and for a mesh with no triangle of positive area.
pub fn read_point_cloud_with(bytes: &[u8], file_name: &str, options: &ReadOptions) -> Result<PointCloud> {
    let (bytes, _) = after_bom(bytes)?;
    let format = detect_format(bytes, file_name)?;
    if bytes.is_empty() {
        return Err(Error::parse(format.name(), "the file is empty (0 bytes)"));
    }
    if let Some(n) = options.surface_points {
        if n < crate::cloud::MIN_POINTS {
            return Err(Error::InvalidOption(format!(
                "surfacePoints = {n} is fewer than {} (the fewest points a registration takes)",
                crate::cloud::MIN_POINTS
            )));
        }
        if n > crate::limits::MAX_FILE_POINTS {
            return Err(Error::InvalidOption(format!(
                "surfacePoints = {n} is more than the {} points a cloud read from a file may hold",
                crate::limits::MAX_FILE_POINTS
            )));
        }
    }
    check_scan(format, options.scan)?;
    if options.classes.is_some() && format != Format::Las {
        return Err(Error::InvalidOption(format!(
            "the classes option keeps points of some LAS classes, but this is a {} file: only LAS and LAZ files \
             hold classifications (leave it unset)",
            format.name()
        )));
    }
    if let Some(min) = options.min_opacity {
        check_min_opacity(format, min, options)?;
    }
    let faces = if options.surface_points.is_some() { Faces::IfAny } else { Faces::Skip };
    let mut raw = read_format(bytes, format, faces, options.scan, options.classes)?;
    if let Some(min) = options.min_opacity {
        raw.vertices = opaque(bytes, raw.vertices, min)?;
    }
    crate::limits::check_file_points(format.name(), raw.vertices.len() as u64)?;
    if raw.vertices.is_empty() {
        return Err(Error::parse(format.name(), "the file holds no points"));
    }
    match options.surface_points {
        Some(n) if !raw.triangles.is_empty() => {
            let points = mesh::sample_triangles(&raw.vertices, &raw.triangles, n, options.seed)?;
            Ok(PointCloud::from_points_f64(&points))
        }
        _ => Ok(raw.into_cloud()),
    }
}

/// Refuses a `minOpacity` out of [0, 1], with `surfacePoints`, or for a format other than PLY.
fn check_min_opacity(format: Format, min: f64, options: &ReadOptions) -> Result<()> {
    if !(0.0..=1.0).contains(&min) {
        return Err(Error::InvalidOption(format!(
            "minOpacity = {} must be a number in [0, 1]",
            crate::error::num(min)
        )));
    }
    if format != Format::Ply {
        return Err(Error::InvalidOption(format!(
            "the minOpacity option keeps the opaque splats of a Gaussian splat PLY, but this is a {} file (leave it \
             unset)",
            format.name()
        )));
    }
    if options.surface_points.is_some() {
        return Err(Error::InvalidOption(
            "minOpacity keeps splats, surfacePoints samples a mesh's faces: give one of them".into(),
        ));
    }
    Ok(())
}

/// The `vertices` of the PLY file `bytes` whose `opacity` logit's sigmoid is at least `min`; an
/// error when the file has no `opacity` or none is that opaque (naming the most opaque).
fn opaque(bytes: &[u8], vertices: Vec<[f64; 3]>, min: f64) -> Result<Vec<[f64; 3]>> {
    let logits = ply::read_vertex_property(bytes, "opacity")?.ok_or_else(|| {
        Error::InvalidOption(
            "the minOpacity option keeps the opaque splats of a Gaussian splat PLY, but this PLY has no vertex \
             'opacity' property (leave it unset)"
                .into(),
        )
    })?;
    let sigmoid = |logit: f64| 1.0 / (1.0 + (-logit).exp());
    let kept: Vec<[f64; 3]> =
        vertices.iter().zip(&logits).filter(|(_, &l)| sigmoid(l) >= min).map(|(v, _)| *v).collect();
    if kept.is_empty() {
        let most = logits.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        return Err(Error::InvalidOption(format!(
            "minOpacity = {}: no splat of the file is that opaque (the most opaque: {})",
            crate::error::num(min),
            crate::error::num(sigmoid(most))
        )));
    }
    Ok(kept)
}

/// Reads a triangle mesh (OBJ, OFF, STL, glTF/GLB, or PLY with a `face` element) from a file's bytes;
/// polygons are fan-triangulated, faces with fewer than three corners are dropped, and an
/// out-of-range vertex index is an error.
pub fn read_mesh(bytes: &[u8], file_name: &str) -> Result<Mesh> {
    let (bytes, _) = after_bom(bytes)?;
    let format = detect_format(bytes, file_name)?;
    if !format.has_faces() {
        return Err(Error::parse(format.name(), "this format holds points only, not a mesh (use read_point_cloud)"));
    }
    Ok(read_format(bytes, format, Faces::Required, None, None)?.into_mesh())
}

/// Writes a cloud as binary little-endian PLY, in the caller's frame: `float x y z` per vertex
/// when the cloud's origin is zero, else `double x y z` (`origin + points[i]`), so large
/// coordinates keep their shape.
pub fn write_ply_binary(cloud: &PointCloud) -> Vec<u8> {
    ply::write_binary(cloud)
}

pub use classes::Classes;
pub use las_transform::transform_las;
#[cfg_attr(not(target_arch = "wasm32"), allow(unused_imports))]
pub(crate) use motion::check_similarity;
pub use pcd_transform::transform_pcd;
pub use ply_transform::transform_ply;
pub use text_transform::transform_text;
pub use transform::{can_transform, transform_file, transform_file_with};

/// Reads a point cloud from a file (native only); the format comes from the file name.
#[cfg(not(target_arch = "wasm32"))]
pub fn read_path(path: &std::path::Path) -> Result<PointCloud> {
    read_path_with(path, &ReadOptions::default())
}

/// [`read_path`] with [`ReadOptions`] ([`read_point_cloud_with`]; native only).
#[cfg(not(target_arch = "wasm32"))]
pub fn read_path_with(path: &std::path::Path, options: &ReadOptions) -> Result<PointCloud> {
    read_point_cloud_with(&read_file(path)?, &file_name(path), options)
}

/// A file's bytes, as [`read_path_with`] reads them: an I/O error names the path (native only).
#[cfg(not(target_arch = "wasm32"))]
pub fn read_file(path: &std::path::Path) -> Result<Vec<u8>> {
    read_file_within(path, crate::limits::MAX_READ_BYTES)
}

/// [`read_file`] with the most bytes it may hold.
#[cfg(not(target_arch = "wasm32"))]
fn read_file_within(path: &std::path::Path, limit: u64) -> Result<Vec<u8>> {
    use std::io::Read;
    let io = |e: std::io::Error| Error::Io(std::io::Error::new(e.kind(), format!("{}: {e}", path.display())));
    let file = std::fs::File::open(path).map_err(io)?;
    // a regular file's length reserves its bytes; a device or pipe's reads stop one byte past the
    // limit
    let size = file.metadata().map(|m| m.len()).unwrap_or(0).min(limit);
    let mut bytes = Vec::with_capacity(size as usize);
    file.take(limit + 1).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > limit {
        return Err(Error::TooLarge(format!(
            "{}: more than {limit} bytes, the most a file read whole may hold (a device or pipe that never ends?)",
            path.display()
        )));
    }
    Ok(bytes)
}

/// The name [`read_path_with`] gives the readers for `path` (its last component; the format
/// comes from its extension).
pub fn file_name(path: &std::path::Path) -> String {
    path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()
}

#[cfg(all(test, unix))]
mod tests {
    /// A device that never ends is refused at the limit, not read until memory runs out.
    #[test]
    fn a_file_that_never_ends_is_refused_at_the_limit() {
        let e = super::read_file_within(std::path::Path::new("/dev/zero"), 1 << 20).unwrap_err().to_string();
        assert!(e.contains("/dev/zero: more than 1048576 bytes") && e.contains("never ends"), "{e}");
        assert_eq!(super::read_file_within(std::path::Path::new("/dev/null"), 1 << 20).unwrap(), Vec::<u8>::new());
    }
}
