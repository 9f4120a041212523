//! `arps register`: each source onto the target, the answer printed (text or JSON), and the
//! moved source written where `--aligned` says.

use crate::{load_registrar, up_axis};
use arps::{io, transform, IcpKind, IcpLoss, NonFinite, Options, Outliers, Start, Support};
use clap::{Args, ValueEnum};
use std::path::{Path, PathBuf};

#[derive(Clone, Copy, ValueEnum)]
enum SearchArg {
    /// The first start, then the others in stages (the global ones, then the other local ones),
    /// stopping at a confident answer.
    Adaptive,
    /// Every start refined, the best by fitness.
    Exhaustive,
    /// Every start refined, the best kept where it is: a better pose the confidence's probes
    /// find is offered among the alternatives, not taken (with `--starts initial` and
    /// `--initial-transform`, a refinement of that guess alone).
    Local,
}

#[derive(Clone, Copy, ValueEnum)]
enum IcpArg {
    /// Point-to-point ICP.
    Point,
    /// Point-to-plane ICP (default).
    Plane,
    /// No refinement.
    Off,
}

#[derive(Clone, Copy, ValueEnum)]
enum LossArg {
    /// Every pair alike (least squares), throughout.
    Squared,
    /// Tukey's biweight on the refinement of an initial transform and on the answer's last
    /// refinement, kept where it fits clearly more of the source (default).
    Robust,
}

/// The options of `arps register`.
#[derive(Args)]
pub struct RegisterArgs {
    /// Source cloud(s) (PLY, PCD, LAS/LAZ, E57, XYZ/PTS/CSV, OBJ, OFF, STL, glTF/GLB).
    #[arg(required = true, num_args = 1..)]
    sources: Vec<PathBuf>,
    /// Target cloud.
    target: PathBuf,
    /// Weights file (safetensors); default: the embedded model.
    #[arg(long)]
    weights: Option<PathBuf>,
    /// Refinement after the network.
    #[arg(long, value_enum, default_value_t = IcpArg::Plane)]
    icp: IcpArg,
    /// Final ICP max correspondence distance, in the clouds' units (default: 2.5% of their
    /// half-extent, or six point spacings of the sparser cloud where that is less: a dense scene).
    #[arg(long)]
    max_correspondence_distance: Option<f64>,
    /// Iteration cap of each ICP stage [default: the engine's `Options::icp_max_iterations`].
    #[arg(long)]
    icp_max_iterations: Option<u32>,
    /// How ICP weighs its pairs (`Options::icp_loss`): `robust` weighs down a surface that
    /// changed between the scans (erosion, construction, moved objects), `squared` is least
    /// squares throughout.
    #[arg(long, value_enum, default_value_t = LossArg::Robust)]
    icp_loss: LossArg,
    /// Points per cloud fed to the network (default: the model's N).
    #[arg(long)]
    network_points: Option<usize>,
    /// Seed of the registration's random choices (the network's point sampling, the global
    /// stage's hypotheses; `Options::seed`).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// ICP's voxel size, in the clouds' units (`Options::voxel_size`; 0 keeps every point)
    /// [default: half the final max correspondence distance, or of the default one when that is
    /// smaller].
    #[arg(long, allow_negative_numbers = true)]
    voxel_size: Option<f64>,
    /// Leave the network out: ICP starts from the initial transform and the other starts
    /// (`Options::network`).
    #[arg(long)]
    no_network: bool,
    /// Where ICP starts from, comma-separated, from network, centroids, initial, turned,
    /// turnedInitial, global, globalNetwork, rotations, rotationsNetwork; the best refinement by fitness wins
    /// [default: the engine's `Options::starts`].
    #[arg(long, value_delimiter = ',')]
    starts: Option<Vec<Start>>,
    /// Search the starts in stages and stop at a confident answer (adaptive), or refine
    /// them all (exhaustive).
    #[arg(long, value_enum, default_value_t = SearchArg::Adaptive)]
    search: SearchArg,
    /// The direction that is up in both clouds, x,y,z (e.g. 0,0,1), when both were captured
    /// level: the answer then only turns the source about it (`Options::up`).
    #[arg(long, value_delimiter = ',', num_args = 1, allow_hyphen_values = true)]
    up: Option<Vec<f64>>,
    /// The share of the source that lies on the target once aligned, when known (1 for a scan
    /// onto a complete model of it): an answer that covers clearly less is not taken as sure
    /// (`Options::source_overlap`).
    #[arg(long, value_name = "SHARE")]
    source_overlap: Option<f64>,
    /// An initial guess of the transform (`Options::initial_transform`): 16 numbers, comma-separated,
    /// the 4x4 row by row (r00,r01,r02,tx,r10,...,0,0,0,1), rigid to 1e-3; with `--starts initial`
    /// ICP starts from it alone.
    #[arg(long, value_delimiter = ',', num_args = 1, allow_hyphen_values = true, value_name = "R00,R01,...")]
    initial_transform: Option<Vec<f64>>,
    /// Drop NaN/Inf points instead of failing.
    #[arg(long)]
    drop_non_finite: bool,
    /// Keep the points that lie far out from the rest of their cloud (by default they are
    /// left out, with a warning: `Options::outliers`).
    #[arg(long)]
    keep_outliers: bool,
    /// Keep a support plane (the table or floor under a scanned object; by default it is
    /// left out, with a warning: `Options::support_plane`).
    #[arg(long)]
    keep_support: bool,
    /// Read a mesh file (OBJ, OFF, STL, glTF/GLB, PLY with faces) as this many points drawn uniformly
    /// over its surface instead of its vertices (a CAD model's vertices sit on its edges);
    /// point files are read as they are.
    #[arg(long)]
    surface_points: Option<usize>,
    /// Seed of the surface sampling of `--surface-points` (`ReadOptions::seed`; the JS
    /// package's read option `seed`), apart from `--seed`.
    #[arg(long, default_value_t = 0)]
    surface_seed: u64,
    /// Of a source E57 file holding several scans, only this one (0-based), placed by its
    /// pose (by default every scan, as one cloud); other formats are read as they are.
    #[arg(long)]
    source_scan: Option<usize>,
    /// Of a target E57 file holding several scans, only this one (0-based); see `--source-scan`.
    #[arg(long)]
    target_scan: Option<usize>,
    /// Of a source LAS or LAZ file, only the points of these classification codes,
    /// comma-separated (ASPRS: 2 ground, 3-5 vegetation, 6 building, 7 low noise, 18 high
    /// noise; e.g. `--source-classes 2` for the ground alone); an error for other formats.
    /// `--aligned` to the source's own format moves every point of the file.
    #[arg(long, value_name = "CODES", value_delimiter = ',')]
    source_classes: Vec<u8>,
    /// Of a target LAS or LAZ file, only the points of these classification codes; see
    /// `--source-classes`.
    #[arg(long, value_name = "CODES", value_delimiter = ',')]
    target_classes: Vec<u8>,
    /// Of a source Gaussian splat PLY, only the splats at least this opaque (0 to 1: the
    /// sigmoid of the file's `opacity` logit; 0.5 keeps logits of 0 or more): the floaters
    /// and huge background splats left out. An error for other files. `--aligned` to the
    /// source's own format moves every splat (turned and scaled with the scene).
    #[arg(long, value_name = "OPACITY")]
    source_min_opacity: Option<f64>,
    /// Of a target Gaussian splat PLY, only the splats at least this opaque; see
    /// `--source-min-opacity`.
    #[arg(long, value_name = "OPACITY")]
    target_min_opacity: Option<f64>,
    /// The factor from the source's unit to the target's, when they differ (e.g. 1000 for a
    /// scan in metres onto a model in millimetres; the option `sourceScale`): distances and
    /// `--aligned` are then in the target's unit. The printed `T_target_source` maps the file's
    /// own points into the target frame, its 3x3 part the rotation times FACTOR; `--json` gives
    /// the factor as `sourceScale` too.
    #[arg(long, value_name = "FACTOR", allow_negative_numbers = true)]
    source_scale: Option<f64>,
    /// Exit with status 1 (after printing every answer) when an answer's confidence is below C,
    /// for unattended batches: stderr says how many were. An error (a file that cannot be read,
    /// a source that failed) exits 2, as a mistyped flag does. An answer another pose fits about
    /// as well as is held at 0.5 exactly: a C above 0.5 fails it.
    #[arg(long, value_name = "C", allow_negative_numbers = true)]
    min_confidence: Option<f64>,
    /// Write each source, moved by its answer into the target's frame, to PATH. To a PATH of the
    /// source's own format (PLY, PCD, XYZ/PTS/TXT/CSV, OBJ, OFF, STL, LAS, LAZ, E57, GLB), the source
    /// file as itself, moved: every attribute kept (colours, intensity, other
    /// fields and columns, faces, LAS's header updated), normals turned, coordinates stored as the
    /// file stored them (an E57 file's scans by their poses; with `--source-scan`, an E57 file of
    /// that scan alone). To a `.ply` PATH, the points read,
    /// in binary PLY (`double` coordinates when they are far from zero, else `float`).
    /// With several sources PATH must hold `{stem}`, replaced by each source file's name
    /// without its extension (e.g. `out/{stem}-aligned.ply`). An input file is never
    /// overwritten. A file that cannot be written (a folder without room or rights) fails its
    /// source, after the answer is printed.
    #[arg(long, value_name = "PATH")]
    aligned: Option<PathBuf>,
    /// Print exactly one JSON object on stdout: the engine's result (`arps::Registration`), fields
    /// camelCase, transforms as 16 column-major numbers, like the JS API's result; plus
    /// `wallMs`, the milliseconds of reading both files and registering, and `source`, the
    /// source's path. With several sources, one such line per source (JSON Lines; reading the
    /// target counts in the first's `wallMs`). A source that failed gives `{"source", "error"}`
    /// instead (one source or several; the exit status is then 2), and a target that could not be
    /// read `{"target", "error"}` alone. A registered source whose `--aligned` file could not be
    /// written gives its result with `alignedError` (the exit status is 2 too).
    #[arg(long)]
    json: bool,
}

/// `register --json`: the engine's result as it is (`arps::contract`: the same fields as the JS
/// result), plus the CLI's own wall-clock time.
#[derive(serde::Serialize)]
#[serde(rename_all = "camelCase")]
struct JsonOutput<'a> {
    /// The source's path.
    #[serde(skip_serializing_if = "Option::is_none")]
    source: Option<String>,
    #[serde(flatten)]
    result: &'a arps::Registration,
    /// Where the aligned source was written (`--aligned`).
    #[serde(skip_serializing_if = "Option::is_none")]
    aligned: Option<String>,
    /// Why the aligned source could not be written (`--aligned`); the answer stands.
    #[serde(skip_serializing_if = "Option::is_none")]
    aligned_error: Option<String>,
    /// `--source-scale`: the 3x3 part of `T_target_source` is the rotation times it.
    #[serde(skip_serializing_if = "Option::is_none")]
    source_scale: Option<f64>,
    /// Reading both files and registering, in-process (model loading excluded), milliseconds.
    wall_ms: f64,
}

fn read_cloud(path: &Path, options: &io::ReadOptions) -> Result<arps::PointCloud, String> {
    io::read_path_with(path, options).map_err(|e| read_error(path, &e, "target"))
}

/// A reader's error on the file at `path`, its read options named as the flags of `side`
/// (`source` or `target`): "the scan option" as `--source-scan`, say.
fn read_error(path: &Path, e: &arps::Error, side: &str) -> String {
    let message = e.to_string().replace("the scan option", &format!("--{side}-scan"));
    let message = message.replace("the classes option", &format!("--{side}-classes"));
    let message = message.replace("the minOpacity option", &format!("--{side}-min-opacity"));
    format!("{}: {}", path.display(), message.replace("minOpacity =", &format!("--{side}-min-opacity")))
}

/// A warning when the file at `path` is a mesh with faces and so was read as its vertices (an
/// STL; an OBJ with an `f` line; an OFF or a PLY whose header counts faces): a CAD model's
/// vertices sit on its edges and corners, not over its surface, which `--surface-points N` reads.
/// A point list saved as OBJ, OFF or PLY gets none.
fn read_as_vertices(path: &Path) -> Option<String> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    // a header: the file's first 64 KiB
    let head = || -> Option<String> {
        let mut head = vec![0u8; 1 << 16];
        let n = std::io::Read::read(&mut std::fs::File::open(path).ok()?, &mut head).ok()?;
        Some(String::from_utf8_lossy(&head[..n]).into_owned())
    };
    let mesh = match ext.as_str() {
        "stl" => true,
        // faces follow the vertices: the whole file
        "obj" => std::fs::read(path).ok()?.split(|&b| b == b'\n').any(|l| l.trim_ascii_start().starts_with(b"f ")),
        // `OFF`, then (past comments) `vertices faces edges`
        "off" => head()?
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && !l.starts_with('#'))
            .nth(1)
            .and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
            .is_some_and(|faces| faces > 0),
        // `element face N` with N > 0
        "ply" => head()?.split("end_header").next().unwrap_or("").lines().any(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            w.len() == 3 && w[0] == "element" && w[1] == "face" && w[2].parse::<u64>().is_ok_and(|k| k > 0)
        }),
        _ => false,
    };
    mesh.then(|| {
        format!(
            "{} is a mesh, read as its vertices, which sit on its edges and corners rather than over its surface: \
             --surface-points N reads N points over its surface (what a CAD model should be read as)",
            path.display()
        )
    })
}

/// A source file read once: its cloud (as [`read_cloud`] reads it), and its bytes when `keep`
/// (what `--aligned` moves as it is).
fn read_source(
    path: &Path,
    options: &io::ReadOptions,
    keep: bool,
) -> Result<(arps::PointCloud, Option<Vec<u8>>), String> {
    let at = |e: arps::Error| read_error(path, &e, "source");
    let bytes = io::read_file(path).map_err(at)?;
    let cloud = io::read_point_cloud_with(&bytes, &io::file_name(path), options).map_err(at)?;
    Ok((cloud, keep.then_some(bytes)))
}

/// Prints one registration of `arps register`: the text report, or one JSON line (`--json`);
/// `source` names the source (in the text report, given when several were), `aligned` where the
/// moved source was written (`--aligned`), or why it could not be, `source_scale` the
/// `--source-scale` its points were multiplied by.
fn print_registration(
    r: &arps::Registration,
    time_ms: f64,
    json: bool,
    source: Option<String>,
    aligned: Option<Result<String, String>>,
    far_centre: Option<[f64; 3]>,
    source_scale: Option<f64>,
) -> Result<(), String> {
    if let Some(source) = source.as_ref().filter(|_| !json) {
        out!("source {source}");
    }
    if json {
        let (aligned, aligned_error) = match aligned {
            Some(Ok(path)) => (Some(path), None),
            Some(Err(e)) => (None, Some(e)),
            None => (None, None),
        };
        let out = serde_json::to_string(&JsonOutput {
            source,
            result: r,
            aligned,
            aligned_error,
            source_scale,
            wall_ms: time_ms,
        })
        .map_err(|e| format!("internal: {e}"))?;
        out!("{out}");
    } else {
        match source_scale {
            Some(f) => out!(
                "T_target_source (maps the source's points, in their own unit, into the target frame: its 3x3 part is the \
                 rotation times {f} (--source-scale); to 12 decimals, --json for every digit):"
            ),
            None => {
                out!("T_target_source (maps source points into the target frame; to 12 decimals, --json for every digit):")
            }
        }
        for row in transform::to_rows(&r.T_target_source) {
            out!("{}", matrix_row(&row));
        }
        let mut rigid = r.T_target_source;
        rigid.fixed_view_mut::<3, 3>(0, 0).unscale_mut(source_scale.unwrap_or(1.0));
        out!(
            "rotation {:.3} deg, translation {:.6}",
            transform::rotation_angle_deg(&rigid),
            transform::translation(&r.T_target_source).norm()
        );
        if let Some(c) = far_centre {
            // far from (0, 0, 0) (a map grid) the translation is that of a far point
            let moved = r.T_target_source.transform_point(&nalgebra::Point3::from(c)) - nalgebra::Point3::from(c);
            out!(
                "the source's centre moves by {:.6} (the translation above is that of (0, 0, 0), far from it)",
                moved.norm()
            );
        }
        out!(
            "fitness {:.4} (within {:.4}), inlier RMSE {:.6}, ICP from the {} start, {} iterations ({})",
            r.fitness,
            r.max_correspondence_distance,
            r.inlier_rmse,
            r.start.name(),
            r.icp_iterations,
            if r.icp_converged { "converged" } else { "not converged" }
        );
        out!("confidence {:.3}", r.confidence);
        for (k, a) in r.alternatives.iter().enumerate() {
            out!(
                "alternative {} (fits about as well): fitness {:.4}, inlier RMSE {:.6}",
                k + 1,
                a.fitness,
                a.inlier_rmse
            );
            for row in transform::to_rows(&a.T_target_source) {
                out!("{}", matrix_row(&row));
            }
        }
        let t = r.timings;
        out!(
            "time {time_ms:.1} ms (read+all); preprocess {:.1}, network {:.1}, GMR {:.2}, ICP {:.1} ms",
            t.preprocess_ms,
            t.network_ms,
            t.gmr_ms,
            t.icp_ms
        );
        for w in &r.warnings {
            out!("warning: {}", in_flags(w));
        }
        match aligned {
            Some(Ok(path)) => out!("wrote the aligned source to {path}"),
            Some(Err(e)) => out!("the aligned source was not written (the answer above stands): {e}"),
            None => {}
        }
    }
    Ok(())
}

/// The centre of `cloud`'s bounds, in its frame, when it lies farther from (0, 0, 0) than ten
/// times the cloud's size (map-grid coordinates), else `None`.
fn far_centre(cloud: &arps::PointCloud) -> Option<[f64; 3]> {
    let (centre, half) = arps::cloud::JointNormalization::box_of(cloud);
    let c: [f64; 3] = std::array::from_fn(|k| cloud.origin[k] + centre[k]);
    (nalgebra::Vector3::from(c).norm() > 10.0 * 2.0 * half).then_some(c)
}

/// `message` (the engine's, which names its options) with the options this command sets by a
/// flag named by that flag.
fn in_flags(message: &str) -> String {
    message
        .replace("`nonFinite: \"drop\"`", "--drop-non-finite")
        .replace("`outliers: \"keep\"`", "--keep-outliers")
        .replace("`supportPlane: \"keep\"`", "--keep-support")
        .replace("maxCorrespondenceDistance", "--max-correspondence-distance")
        .replace("voxelSize", "--voxel-size")
        .replace("icpMaxIterations", "--icp-max-iterations")
        .replace("networkPoints", "--network-points")
        .replace("initialTransform", "--initial-transform")
        .replace("sourceOverlap", "--source-overlap")
        .replace("sourceScale", "--source-scale")
}

/// True when `path` names a file of `source`'s own format that `io::transform_file` moves as it
/// is (`scan.pcd` to `out.pcd`, `a.pts` to `b.xyz`, a LAS source to `out.las`, a LAZ source to
/// `out.laz`: LAZ comes back compressed, LAS not).
fn moves_as_it_is(source: &Path, path: &Path) -> bool {
    let name = |p: &Path| p.to_string_lossy().into_owned();
    let (source, path) = (name(source), name(path));
    let laz = |name: &str| name.to_ascii_lowercase().ends_with(".laz");
    io::can_transform(&source)
        && io::can_transform(&path)
        && laz(&source) == laz(&path)
        && io::Format::from_file_name(&source) == io::Format::from_file_name(&path)
}

/// Where `--aligned PATTERN` writes the aligned `source`: `{stem}` replaced by the source file's
/// name without its extension. Refuses a path that does not say what is written (the source's
/// own format when it can be moved as it is, or `.ply`), that is one of the `inputs` (the same
/// file, however named: through a link too), or whose folder does not exist.
fn aligned_path(pattern: &Path, source: &Path, inputs: &[&Path]) -> Result<PathBuf, String> {
    let stem = source.file_stem().map(|s| s.to_string_lossy()).unwrap_or_default();
    let path = PathBuf::from(pattern.to_string_lossy().replace("{stem}", &stem));
    let is_ply = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    if !(is_ply || moves_as_it_is(source, &path)) {
        let own = source.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
        let what = match own.as_deref() {
            Some(ext) if io::can_transform(&source.to_string_lossy()) && ext != "ply" => {
                format!(".{ext} (the source moved as it is) or .ply (its points)")
            }
            _ => ".ply".to_string(),
        };
        return Err(format!(
            "--aligned: {} is not a name it can write for {}: name a {what} file",
            path.display(),
            source.display()
        ));
    }
    if let Some(input) = inputs.iter().find(|input| same_file(&path, input)) {
        return Err(format!("--aligned: {} is an input file ({}); name another file", path.display(), input.display()));
    }
    let folder = path.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(folder) = folder.filter(|f| !f.is_dir()) {
        return Err(format!("--aligned: the folder {} does not exist", folder.display()));
    }
    Ok(path)
}

/// True when `a` and `b` name the same file: the same path once resolved, or (on Unix) the same
/// file through another hard link.
fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return x.dev() == y.dev() && x.ino() == y.ino();
        }
    }
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}

/// Writes the source moved by `r`'s answer to `path`: to a path of the source's own format, the
/// source file (`bytes`, the file `file` as read for registering) as itself, moved
/// (`io::transform_file_with` and the options it was read with, `reading`: PLY, PCD, text lists,
/// OBJ, OFF, STL, LAS, LAZ, E57, glTF, one scan of an E57 file as an E57 file of that scan; every
/// attribute kept, normals turned); else (a `.ply` path) as the points read (`cloud`) in binary PLY
/// (`io::write_ply_binary`). `r`'s answer maps the file's own points (times `--source-scale`).
fn write_aligned(
    file: &Path,
    bytes: &[u8],
    reading: &io::ReadOptions,
    cloud: &arps::PointCloud,
    r: &arps::Registration,
    path: &Path,
) -> Result<(), String> {
    let m = r.T_target_source;
    let out = if moves_as_it_is(file, path) {
        io::transform_file_with(bytes, &io::file_name(file), &m, reading)
            .map_err(|e| format!("--aligned: {}: {e}", file.display()))?
    } else {
        io::write_ply_binary(&cloud.placed(&r.T_target_source))
    };
    // written beside it, then renamed over it: a file it replaces (a link to an input, say) is
    // never half written or written through
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let partial = path.with_file_name(format!(".{name}.{}.partial", std::process::id()));
    let written = std::fs::write(&partial, out).and_then(|()| std::fs::rename(&partial, path));
    written.map_err(|e| {
        let _ = std::fs::remove_file(&partial);
        format!("--aligned: {}: {e}", path.display())
    })
}

/// Registers each source onto the target (see [`RegisterArgs`]).
pub fn run(args: RegisterArgs) -> Result<Option<String>, String> {
    let RegisterArgs {
        sources,
        target,
        weights,
        icp,
        max_correspondence_distance,
        icp_max_iterations,
        icp_loss,
        network_points,
        seed,
        voxel_size,
        no_network,
        starts,
        search,
        up,
        source_overlap,
        initial_transform,
        drop_non_finite,
        keep_outliers,
        keep_support,
        surface_points,
        surface_seed,
        source_scan,
        target_scan,
        source_classes,
        target_classes,
        source_min_opacity,
        target_min_opacity,
        source_scale,
        min_confidence,
        aligned,
        json,
    } = args;
    if let Some(c) = min_confidence.filter(|c| !(0.0..=1.0).contains(c)) {
        return Err(format!("--min-confidence: expected a number in [0, 1], got {c}"));
    }
    let up = up.map(|v| up_axis(&v)).transpose()?;
    if let Some(s) = source_scale.filter(|s| !(s.is_finite() && *s > 0.0)) {
        return Err(format!("--source-scale: expected a finite number > 0, got {s}"));
    }
    if let Some(pattern) = aligned.as_ref().filter(|p| sources.len() > 1 && !p.to_string_lossy().contains("{stem}")) {
        return Err(format!(
            "--aligned: with {} sources the path must hold {{stem}} (each source's name), e.g. {{stem}}-aligned.ply; got {}",
            sources.len(),
            pattern.display()
        ));
    }
    let inputs: Vec<&Path> = sources.iter().map(PathBuf::as_path).chain([target.as_path()]).collect();
    let outputs = match &aligned {
        Some(pattern) => {
            sources.iter().map(|s| aligned_path(pattern, s, &inputs).map(Some)).collect::<Result<Vec<_>, _>>()?
        }
        None => vec![None; sources.len()],
    };
    for (k, path) in outputs.iter().enumerate().filter_map(|(k, p)| Some((k, p.as_ref()?))) {
        if let Some(j) = outputs[..k].iter().position(|q| q.as_ref() == Some(path)) {
            return Err(format!(
                "--aligned: sources {} and {} would both be written to {}; put more of the name in the path",
                sources[j].display(),
                sources[k].display(),
                path.display()
            ));
        }
    }
    let mut registrar = load_registrar(weights.as_deref())?;
    let mut t0 = std::time::Instant::now();
    let classes = |codes: Vec<u8>| (!codes.is_empty()).then(|| io::Classes::of(codes));
    let reading = io::ReadOptions {
        surface_points,
        seed: surface_seed,
        scan: source_scan,
        classes: classes(source_classes),
        min_opacity: source_min_opacity,
    };
    let reading_target = io::ReadOptions {
        scan: target_scan,
        classes: classes(target_classes),
        min_opacity: target_min_opacity,
        ..reading
    };
    let initial_transform = match initial_transform.as_deref() {
        None => None,
        Some(v) if v.len() == 16 => Some(std::array::from_fn(|r| std::array::from_fn(|c| v[4 * r + c]))),
        Some(v) => {
            return Err(format!("--initial-transform: expected 16 numbers (a 4x4, row by row), got {}", v.len()))
        }
    };
    let options = Options {
        initial_transform,
        icp: match icp {
            IcpArg::Point => IcpKind::Point,
            IcpArg::Plane => IcpKind::Plane,
            IcpArg::Off => IcpKind::Off,
        },
        max_correspondence_distance,
        icp_max_iterations: icp_max_iterations.unwrap_or(Options::default().icp_max_iterations),
        icp_loss: match icp_loss {
            LossArg::Squared => IcpLoss::Squared,
            LossArg::Robust => IcpLoss::Robust,
        },
        network_points,
        seed,
        voxel_size,
        network: !no_network,
        non_finite: if drop_non_finite { NonFinite::Drop } else { NonFinite::Error },
        outliers: if keep_outliers { Outliers::Keep } else { Outliers::Drop },
        support_plane: if keep_support { Support::Keep } else { Support::Drop },
        up,
        source_overlap,
        source_scale,
        starts: starts.unwrap_or_else(|| Options::default().starts),
        search: match search {
            SearchArg::Adaptive => arps::Search::Adaptive,
            SearchArg::Exhaustive => arps::Search::Exhaustive,
            SearchArg::Local => arps::Search::Local,
        },
    };
    // the target is read once; the registrar keeps it prepared from one source to the next
    let tgt = read_cloud(&target, &reading_target).inspect_err(|e| {
        // (a script reading stdout sees the failure as JSON, as it does a source's)
        if json {
            out!("{}", serde_json::json!({ "target": target.display().to_string(), "error": e }));
        }
    })?;
    // a mesh read as its vertices (no --surface-points): said with each answer
    let vertices_warning = |path: &Path| (surface_points.is_none()).then(|| read_as_vertices(path)).flatten();
    let target_vertices = vertices_warning(&target);
    let several = sources.len() > 1;
    let mut failed = 0usize;
    let mut unsure = 0usize;
    for (source, output) in sources.iter().zip(&outputs) {
        let read = read_source(source, &reading, output.is_some());
        let outcome = read.and_then(|(src, bytes)| {
            // a cloud the engine refuses is named by its file
            let r = registrar.register(&src, &tgt, &options).map_err(|e| match &e {
                arps::Error::InvalidCloud(m) => {
                    format!("{}: {e}", if m.starts_with("target") { target.display() } else { source.display() })
                }
                _ => e.to_string(),
            })?;
            Ok((src, bytes, r))
        });
        let time_ms = t0.elapsed().as_secs_f64() * 1e3;
        // (the JSON names every source, the text report only one of several)
        let named = (several || json).then(|| source.display().to_string());
        // the moved source written; a failure to write it leaves the answer, which is printed
        // with the error (a registration that worked is not lost to a full disk or a bad path)
        let outcome = outcome.map(|(src, bytes, r)| {
            let aligned = match (output, bytes) {
                (Some(path), Some(bytes)) => Some(
                    write_aligned(source, &bytes, &reading, &src, &r, path)
                        .map(|()| path.display().to_string())
                        .map_err(|e| in_flags(&e)),
                ),
                _ => None,
            };
            (r, far_centre(&src), aligned)
        });
        t0 = std::time::Instant::now();
        match outcome {
            Ok((mut r, centre, aligned)) => {
                for w in vertices_warning(source).into_iter().chain(target_vertices.clone()) {
                    r.warnings.push(w);
                    r.warning_codes.push(arps::WarningCode::MeshVertices);
                }
                unsure += usize::from(min_confidence.is_some_and(|c| r.confidence < c));
                let not_written = aligned.as_ref().and_then(|a| a.as_ref().err()).cloned();
                print_registration(&r, time_ms, json, named, aligned, centre, source_scale)?;
                match not_written {
                    Some(e) if !several => return Err(e),
                    Some(_) => failed += 1,
                    None => {}
                }
            }
            Err(e) if !several => {
                let e = in_flags(&e);
                // (a script reading stdout sees the failure as JSON too, as with several sources)
                if json {
                    out!("{}", serde_json::json!({ "source": named, "error": e }));
                }
                return Err(e);
            }
            Err(e) => {
                let e = in_flags(&e);
                failed += 1;
                if json {
                    out!("{}", serde_json::json!({ "source": named, "error": e }));
                } else {
                    out!("source {}", source.display());
                    out!("error: {e}");
                }
            }
        }
    }
    if failed > 0 {
        return Err(format!("{failed} of {} sources failed", sources.len()));
    }
    Ok((min_confidence.is_some() && unsure > 0).then(|| {
        format!(
            "{unsure} of {} answers have a confidence below --min-confidence {}",
            sources.len(),
            min_confidence.unwrap_or_default()
        )
    }))
}

/// Exit status of `register` when every source was registered but some answer's confidence is
/// below `--min-confidence` (an error exits 2).
pub const UNSURE: u8 = 1;

/// One row of a printed 4x4, to 12 decimals: with fewer, a matrix copied from the terminal moves
/// a survey on a map grid (coordinates near 5e6) by metres (1e-6 of its rotation is 5 there).
fn matrix_row(row: &[f64; 4]) -> String {
    row.iter().map(|v| format!("{:>20.12}", if *v == 0.0 { 0.0 } else { *v })).collect::<Vec<_>>().join(" ")
}
