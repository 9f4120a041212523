//! The WebAssembly binding (wasm-bindgen), compiled only for `wasm32`.
//!
//! A thin layer: it converts JS values to core types and back, and core errors to thrown JS
//! `Error`s. All logic lives in the core ([`crate::Registrar`], [`crate::io`]).
//!
//! JS API (the declarations: `js/arps-contract.d.ts`, generated from the core types, and
//! `js/arps-types.d.ts`, both appended to the generated `arps.d.ts`):
//! * `Registrar.fromBytes(Uint8Array)`, and `Registrar.withDefaultModel()` in builds with the
//!   `embed-model` feature (the package's facade provides it over the model file otherwise);
//! * `registrar.register(source: Float32Array, target: Float32Array, options?, onProgress?)` ->
//!   the core [`crate::Registration`] as a plain object (`RegistrationResult`), serialised by
//!   serde like the CLI's JSON ([`crate::contract`]); the options are the core [`Options`]
//!   (`RegisterOptions`), read by serde;
//! * `parsePointCloud(bytes: Uint8Array, fileName: string) -> Float32Array`;
//! * `readPointCloud(bytes: Uint8Array, fileName: string) -> { points: Float32Array, origin }`;
//! * `transformPointCloud(cloud, matrix) -> { points, origin }` and `writePly(cloud) -> Uint8Array`
//!   (a cloud: a `Float32Array` or `{ points: Float32Array, origin }`);
//! * `transformFile(bytes, fileName, matrix)` -> `Uint8Array` (a file moved as it is, in its own
//!   format) and `canTransform(fileName)`;
//! * `listScans(bytes, fileName)` -> `ScanInfo[]` (an E57 file's scans).
//!
//! Nothing here may panic on user input: a panic in wasm aborts the instance (wasm32 builds with
//! `panic = "abort"`; there is no `catch_unwind`), so every fallible step returns
//! `Result<_, JsError>`. Reading the options object (its keys and top-level values: getters,
//! Proxy traps) and calling the progress callback go through `catch` imports, so those throws
//! become this call's error instead of unwinding through wasm with the registrar borrowed.
//! Deeper values are expected to be plain data: the package's public entry points
//! (`js/facade.js`) copy the options into plain data and check every input before it reaches this
//! binding's glue, and they recover from any trap that still happens (out of memory, an engine
//! bug) by re-instantiating the module.

use crate::{Options, PointCloud};
use js_sys::{Array, Float32Array, Object, Reflect};
use wasm_bindgen::prelude::*;

/// The option and result types (`RegisterOptions`, `RegistrationResult`, ...), generated from
/// the core types ([`crate::contract::typescript`]) and appended to the generated `arps.d.ts`.
#[wasm_bindgen(typescript_custom_section)]
const TS_CONTRACT: &'static str = include_str!("../js/arps-contract.d.ts");

/// The JS-only types (`CloudInput`, `CloudWithOrigin`, `ModelProvenance`), hand-written in
/// `js/arps-types.d.ts` and appended to the generated `arps.d.ts`.
#[wasm_bindgen(typescript_custom_section)]
const TS_TYPES: &'static str = include_str!("../js/arps-types.d.ts");

#[wasm_bindgen]
extern "C" {
    #[wasm_bindgen(js_namespace = performance, js_name = now)]
    fn performance_now() -> f64;

    /// `Object.keys`, with a throw (a Proxy's `ownKeys` trap) returned instead of unwinding.
    #[wasm_bindgen(catch, js_namespace = Object, js_name = keys)]
    fn object_keys(object: &JsValue) -> Result<Array, JsValue>;
}

/// The message of a thrown JS value: its `message` (read through `Reflect.get`, which catches a
/// throwing getter), a thrown string itself, else a placeholder.
fn js_message(e: &JsValue) -> String {
    if let Some(s) = e.as_string() {
        return s;
    }
    if e.is_object() {
        if let Some(m) = Reflect::get(e, &JsValue::from_str("message")).ok().and_then(|m| m.as_string()) {
            return m;
        }
    }
    "a thrown value that is not an Error".to_string()
}

/// The clock handed to the core: `performance.now()` where it exists, else `Date.now()`.
fn clock_performance() -> f64 {
    performance_now()
}

fn clock_date() -> f64 {
    js_sys::Date::now()
}

fn js_clock() -> crate::timing::Clock {
    // `globalThis.performance` exists in browsers, workers and Node >= 16.
    let has_performance = Reflect::get(&js_sys::global(), &JsValue::from_str("performance"))
        .ok()
        .filter(|p| p.is_object())
        .and_then(|p| Reflect::get(&p, &JsValue::from_str("now")).ok())
        .is_some_and(|f| f.is_function());
    if has_performance {
        clock_performance
    } else {
        clock_date
    }
}

/// Installs the panic hook once, so that a core bug (a panic) at least prints its message to
/// the console before the instance traps. Runs when the module is instantiated.
#[wasm_bindgen(start, skip_typescript)]
fn start() {
    console_error_panic_hook::set_once();
}

fn js_err(e: crate::Error) -> JsError {
    JsError::new(&e.to_string())
}

/// The crate version (`"0.1.0"`).
#[wasm_bindgen]
pub fn version() -> String {
    env!("CARGO_PKG_VERSION").to_string()
}

/// Reads a point cloud from a file's bytes with the core readers (PLY, PCD, LAS/LAZ, E57,
/// XYZ/PTS/CSV, OBJ, OFF, STL, glTF/GLB). The format comes from the file's signature (`ply`,
/// `LASF`, `ASTM-E57`, `glTF`, `# .PCD`, `OFF`) when it starts with one, else from its name's extension, else
/// it is sniffed from the content; mesh formats give their
/// vertices, or with `options.surfacePoints` that many points drawn uniformly over their surface
/// (`ReadOptions`: what a CAD model should be read as). Returns packed xyz (`[x0, y0, z0, x1,
/// ...]`). Throws on unreadable input and invalid options.
#[wasm_bindgen(js_name = parsePointCloud)]
pub fn parse_point_cloud(
    #[wasm_bindgen(unchecked_param_type = "ArrayBuffer | ArrayBufferView")] bytes: &[u8],
    #[wasm_bindgen(js_name = "fileName")] file_name: &str,
    #[wasm_bindgen(unchecked_optional_param_type = "ReadOptions | null")] options: Option<JsValue>,
) -> Result<Vec<f32>, JsError> {
    let options = parse_object(options.unwrap_or(JsValue::UNDEFINED), "read options")?;
    let cloud = crate::io::read_point_cloud_with(bytes, file_name, &options).map_err(js_err)?;
    Ok(cloud.to_xyz())
}

/// Reads a point cloud from a file's bytes like [`parse_point_cloud`], keeping the precision of
/// large coordinates: returns `{ points, origin }`, `points` a `Float32Array` of offsets from
/// `origin` (`[x, y, z]`, f64: zero unless the file's coordinates are far from zero relative to
/// the cloud's size, then near the points: a georeferenced LAS/LAZ survey, say). Point `i` is
/// `origin + points[i]`; the object is a cloud `register` accepts as is. `options` as for [`parse_point_cloud`]. Throws on unreadable
/// input and invalid options.
#[wasm_bindgen(js_name = readPointCloud, unchecked_return_type = "CloudWithOrigin")]
pub fn read_point_cloud(
    #[wasm_bindgen(unchecked_param_type = "ArrayBuffer | ArrayBufferView")] bytes: &[u8],
    #[wasm_bindgen(js_name = "fileName")] file_name: &str,
    #[wasm_bindgen(unchecked_optional_param_type = "ReadOptions | null")] options: Option<JsValue>,
) -> Result<JsValue, JsError> {
    let options = parse_object(options.unwrap_or(JsValue::UNDEFINED), "read options")?;
    let cloud = crate::io::read_point_cloud_with(bytes, file_name, &options).map_err(js_err)?;
    cloud_object(&cloud)
}

/// A 4x4 argument: 16 numbers, column-major.
fn matrix_arg(matrix: &[f64]) -> Result<nalgebra::Matrix4<f64>, JsError> {
    if matrix.len() != 16 {
        return Err(JsError::new(&format!("matrix: expected 16 numbers (a 4x4, column-major), got {}", matrix.len())));
    }
    Ok(nalgebra::Matrix4::from_column_slice(matrix))
}

/// A cloud as the JS object `{ points: Float32Array, origin: [x, y, z] }`.
fn cloud_object(cloud: &PointCloud) -> Result<JsValue, JsError> {
    let out = Object::new();
    let points: Vec<f32> = cloud.points.iter().flatten().copied().collect();
    set(&out, "points", &Float32Array::from(&points[..]))?;
    let origin: Array = cloud.origin.iter().map(|v| JsValue::from_f64(*v)).collect();
    set(&out, "origin", &origin)?;
    Ok(out.into())
}

/// A cloud argument: a `Float32Array` of packed xyz, or `{ points: Float32Array, origin }` with
/// `origin` three finite numbers (or `null`/absent for zero). `what` names it in errors.
fn cloud_arg(value: &JsValue, what: &str) -> Result<PointCloud, JsError> {
    let bad = || {
        JsError::new(&format!(
            "{what}: expected a Float32Array of packed xyz, or {{ points: Float32Array, origin: [x, y, z] }}"
        ))
    };
    let field = |key: &str| {
        Reflect::get(value, &JsValue::from_str(key))
            .map_err(|e| JsError::new(&format!("{what}: reading {key} threw: {}", js_message(&e))))
    };
    let (points, origin) = if value.is_instance_of::<Float32Array>() {
        (value.clone(), JsValue::NULL)
    } else if value.is_object() && !Array::is_array(value) {
        (field("points")?, field("origin")?)
    } else {
        return Err(bad());
    };
    if !points.is_instance_of::<Float32Array>() {
        return Err(bad());
    }
    let flat = Float32Array::from(points).to_vec();
    let cloud = PointCloud::from_xyz(&flat).map_err(|e| prefixed(what, e))?;
    if origin.is_undefined() || origin.is_null() {
        return Ok(cloud);
    }
    // anything but an array of three finite numbers is refused (a non-number reads as NaN)
    let o: Vec<f64> = match Array::is_array(&origin) {
        true => Array::from(&origin).iter().map(|v| v.as_f64().unwrap_or(f64::NAN)).collect(),
        false => Vec::new(),
    };
    placed_at(cloud, &o, what)
}

/// `cloud` with its points measured from `origin`, which must be three finite numbers (the error
/// names the cloud `what`).
fn placed_at(cloud: PointCloud, origin: &[f64], what: &str) -> Result<PointCloud, JsError> {
    match *origin {
        [x, y, z] if origin.iter().all(|v| v.is_finite()) => Ok(PointCloud::with_origin(cloud.points, [x, y, z])),
        _ => Err(JsError::new(&format!("{what}: origin must be 3 finite numbers [x, y, z]"))),
    }
}

/// Maps a cloud by a rigid transform (or one times a uniform scale: a result's `T_target_source`
/// with the option `sourceScale`), e.g. a source by the `T_target_source` of its registration
/// into the target's frame: returns `{ points, origin }` (what `register` and `writePly` take),
/// the origin mapped in f64 and the offsets by the rotation, so map-grid coordinates keep their
/// digits; a cloud without an origin is mapped as it is (origin zero), unless the matrix places
/// it so far from zero that float32 would round it (a local scan placed on a map grid): then
/// it gets an origin there too. Read the points as `origin + points[i]`. Any number of points. `matrix`: 16
/// numbers, column-major (what a result's `T_target_source` and three.js `Matrix4.elements`
/// hold), or (through the package's entry) four row-major rows; rigid (or uniformly scaled) to
/// 1e-3 (a matrix written with a few decimals), and applied as given. Throws on a bad cloud or
/// matrix.
#[wasm_bindgen(js_name = transformPointCloud, unchecked_return_type = "CloudWithOrigin")]
pub fn transform_point_cloud(
    #[wasm_bindgen(unchecked_param_type = "CloudInput")] cloud: JsValue,
    #[wasm_bindgen(unchecked_param_type = "ArrayLike<number> | number[][]")] matrix: &[f64],
) -> Result<JsValue, JsError> {
    let m = matrix_arg(matrix)?;
    // checked, then used as given: snapped onto a rotation about the frame's origin, a matrix
    // written with a few decimals would move a cloud on a map grid by metres
    crate::io::check_similarity(&m, "matrix").map_err(|e| match e {
        crate::Error::InvalidOption(m) => JsError::new(&m),
        e => JsError::new(&e.to_string()),
    })?;
    let cloud = cloud_arg(&cloud, "cloud")?;
    cloud_object(&cloud.placed(&m))
}

/// The rigid `T_target_source` that best maps paired points onto each other (least squares):
/// `source[i]` (in the source's frame) pairs with `target[i]` (in the target's), e.g. 3 or more
/// landmarks picked or surveyed in both, for the option `initialTransform`. Each list: packed xyz
/// numbers (an array or a typed array, read as f64) or a list of `[x, y, z]`. Returns
/// `{ T_target_source, rmse }`: 16 numbers, column-major, and the RMS distance between the pairs
/// under it, in the clouds' units (a large one: a pair mismatched, or landmarks picked far off).
/// Throws on lists of different lengths, fewer than 3 pairs, a value that is not finite, and
/// points on one line (or at one point) in either list.
#[wasm_bindgen(js_name = rigidFromPairs, unchecked_return_type = "PairsFit")]
pub fn rigid_from_pairs(
    #[wasm_bindgen(unchecked_param_type = "ArrayLike<number> | number[][]")] source: &[f64],
    #[wasm_bindgen(unchecked_param_type = "ArrayLike<number> | number[][]")] target: &[f64],
) -> Result<JsValue, JsError> {
    let points = |v: &[f64], what: &str| -> Result<Vec<[f64; 3]>, JsError> {
        if !v.len().is_multiple_of(3) {
            return Err(JsError::new(&format!(
                "the pairs: {what} has {} numbers, not a multiple of 3 (x, y, z per point)",
                v.len()
            )));
        }
        Ok(v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
    };
    let (t, rmse) = crate::rigid::fit_pairs(&points(source, "source")?, &points(target, "target")?).map_err(js_err)?;
    let out = Object::new();
    let m: Array = t.as_slice().iter().map(|v| JsValue::from_f64(*v)).collect();
    set(&out, "T_target_source", &m)?;
    set(&out, "rmse", &JsValue::from_f64(rmse))?;
    Ok(out.into())
}

/// A cloud as a binary little-endian PLY file (`x`, `y`, `z` per vertex): `double` coordinates
/// (`origin + points[i]`) when the cloud's origin is not zero, so map-grid coordinates keep their
/// digits, else `float`. With `transformPointCloud`, what saves a registered source in the
/// target's frame. Throws on a bad cloud.
#[wasm_bindgen(js_name = writePly)]
pub fn write_ply(#[wasm_bindgen(unchecked_param_type = "CloudInput")] cloud: JsValue) -> Result<Vec<u8>, JsError> {
    Ok(crate::io::write_ply_binary(&cloud_arg(&cloud, "cloud")?))
}

/// The scans of a file that holds several, in the file's order: for an E57 file its point clouds
/// as `{ name, records }` (`name` a string or `null`, `records` the scan's point records, invalid
/// ones included), read from its XML section alone; for any other format `[]`. A scan is then
/// read alone by `readPointCloud(bytes, fileName, { scan: K })`. Throws on an E57 file that cannot
/// be read.
#[wasm_bindgen(js_name = listScans, unchecked_return_type = "ScanInfo[]")]
pub fn list_scans(
    #[wasm_bindgen(unchecked_param_type = "ArrayBuffer | ArrayBufferView")] bytes: &[u8],
    #[wasm_bindgen(js_name = fileName)] file_name: &str,
) -> Result<JsValue, JsError> {
    let scans = crate::io::list_scans(bytes, file_name).map_err(js_err)?;
    let ser = serde_wasm_bindgen::Serializer::new().serialize_missing_as_null(true);
    serde::Serialize::serialize(&scans, &ser).map_err(|e| JsError::new(&format!("internal: {e}")))
}

/// A file moved as it is, in its own format, e.g. a registered source by its result's
/// `T_target_source`: PLY, PCD, text lists (XYZ, PTS, TXT, CSV), OBJ, OFF, STL, LAS, LAZ
/// (compressed again), E57 (its scans' poses moved, its points kept as
/// stored; rigid motions only) and glTF/GLB (a new parent node above its top nodes, its buffers
/// kept) (see `canTransform`). Positions are mapped in f64 and written back as the file stored them (the
/// property's type, the text's decimals, LAS's scaled integers, with its offsets where the moved
/// points fit them), normals turned,
/// a Gaussian splat PLY's splats turned and scaled with the scene (`rot_*` quaternions, `scale_*`
/// log-extents, `f_rest_*` colour coefficients),
/// everything else kept (colours, intensity, classification, faces, other fields, the header).
/// `fileName` says the format by its extension, where the file does not start with a format's
/// signature (else the content does). `matrix`: 16 numbers,
/// column-major (or, through the package's entry, four row-major rows), a rigid transform or one
/// times a uniform scale (a change of unit). `options`: the `ReadOptions` the cloud was read
/// with; with `scan`, an E57 file's scan alone is saved, as an E57 file of its own (its points'
/// and images' bytes kept, the other scans left out); with `classes`, a LAS file is still moved
/// whole (every point, whatever its class). Returns the moved file's bytes. Throws on a
/// format it cannot tell, a file its reader refuses, integer coordinates where the moved ones
/// cannot be stored, a matrix that is not rigid (or uniformly scaled), and invalid options.
#[wasm_bindgen(js_name = transformFile)]
pub fn transform_file(
    #[wasm_bindgen(unchecked_param_type = "ArrayBuffer | ArrayBufferView")] bytes: &[u8],
    #[wasm_bindgen(js_name = fileName)] file_name: &str,
    #[wasm_bindgen(unchecked_param_type = "ArrayLike<number> | number[][]")] matrix: &[f64],
    #[wasm_bindgen(unchecked_optional_param_type = "ReadOptions | null")] options: Option<JsValue>,
) -> Result<Vec<u8>, JsError> {
    let options = parse_object(options.unwrap_or(JsValue::UNDEFINED), "read options")?;
    crate::io::transform_file_with(bytes, file_name, &matrix_arg(matrix)?, &options).map_err(js_err)
}

/// True when `transformFile` moves a file of this name as it is, by its extension: `.ply .pcd
/// .xyz .pts .txt .csv .obj .off .stl .las .laz .e57 .glb .gltf` (case-insensitive). False for
/// other names; `transformFile` still knows a file of another name by its content (a PLY, PCD,
/// LAS, LAZ, E57 or GLB signature, a text list) and moves it as it is. A file it does not know:
/// save it as `writePly(transformPointCloud(cloud, T))`.
#[wasm_bindgen(js_name = canTransform)]
pub fn can_transform(#[wasm_bindgen(js_name = fileName)] file_name: &str) -> bool {
    crate::io::can_transform(file_name)
}

/// Holds a loaded model and reusable buffers; registers pairs of clouds.
#[wasm_bindgen]
pub struct Registrar {
    inner: crate::Registrar,
}

#[wasm_bindgen]
impl Registrar {
    /// A registrar on the model embedded in the engine (`models/web.safetensors`); only in
    /// builds with the `embed-model` feature. The npm package's engine is built without it: its
    /// facade (`js/facade.js`) loads the model file next to the `.wasm` and passes the bytes to
    /// [`Registrar::from_bytes`].
    #[cfg(feature = "embed-model")]
    #[wasm_bindgen(js_name = withDefaultModel)]
    pub fn with_default_model() -> Result<Registrar, JsError> {
        let mut inner = crate::Registrar::with_default_model().map_err(js_err)?;
        inner.set_clock(Some(js_clock()));
        Ok(Registrar { inner })
    }

    /// A registrar on custom weights (the bytes of an arps `.safetensors` file).
    /// Throws if the bytes are not a valid arps weights file.
    #[wasm_bindgen(js_name = fromBytes)]
    pub fn from_bytes(
        #[wasm_bindgen(unchecked_param_type = "ArrayBuffer | ArrayBufferView")] bytes: &[u8],
    ) -> Result<Registrar, JsError> {
        let mut inner = crate::Registrar::from_bytes(bytes).map_err(js_err)?;
        inner.set_clock(Some(js_clock()));
        Ok(Registrar { inner })
    }

    /// Registers `source` onto `target` (packed xyz, same units) and returns the transform
    /// mapping source points into the target frame, with quality figures. `sourceOrigin` and
    /// `targetOrigin` (three finite numbers each, or absent for zero) are where each cloud's
    /// points are measured from: the caller's points are `origin + points[i]`, and
    /// `T_target_source`, its alternatives, `initialTransform` and the warnings are in the
    /// caller's frames (the package's entry points, `js/facade.js`, also take `Float64Array`s and
    /// `{ points, origin }` clouds and pass them here so). `options` is a
    /// plain object (`RegisterOptions`, or `undefined`/`null`); unknown fields throw. The result
    /// is a plain `RegistrationResult`, the same object as `arps register --json` prints.
    /// `onProgress`, if given, is called with each `RegistrationStage` (`"preparing"`,
    /// `"network"`, `"refining"`) as it starts (stages that do not run are skipped); if it throws,
    /// the registration still completes and then the call throws an `Error` ("onProgress threw:
    /// ...") whose `cause` is the value thrown (the package's facade sets it).
    #[wasm_bindgen(unchecked_return_type = "RegistrationResult")]
    pub fn register(
        &mut self,
        #[wasm_bindgen(unchecked_param_type = "CloudInput")] source: &[f32],
        #[wasm_bindgen(unchecked_param_type = "CloudInput")] target: &[f32],
        #[wasm_bindgen(unchecked_optional_param_type = "RegisterOptions | null")] options: Option<JsValue>,
        #[wasm_bindgen(
            js_name = "onProgress",
            unchecked_optional_param_type = "((stage: RegistrationStage) => void) | null"
        )]
        on_progress: Option<js_sys::Function>,
        #[wasm_bindgen(js_name = "sourceOrigin", unchecked_optional_param_type = "ArrayLike<number> | null")]
        source_origin: Option<Vec<f64>>,
        #[wasm_bindgen(js_name = "targetOrigin", unchecked_optional_param_type = "ArrayLike<number> | null")]
        target_origin: Option<Vec<f64>>,
    ) -> Result<JsValue, JsError> {
        let options = options.unwrap_or(JsValue::UNDEFINED);
        let options = parse_options(options)?;
        let placed = |points: &[f32], origin: Option<Vec<f64>>, what: &str| {
            let cloud = PointCloud::from_xyz(points).map_err(|e| prefixed(what, e))?;
            match origin {
                None => Ok(cloud),
                Some(o) => placed_at(cloud, &o, what),
            }
        };
        let source = placed(source, source_origin, "source")?;
        let target = placed(target, target_origin, "target")?;
        let mut callback_error: Option<JsValue> = None;
        let mut progress = |stage: crate::Stage| {
            if let (Some(f), None) = (&on_progress, &callback_error) {
                let called = to_js(&stage).map_err(JsValue::from).and_then(|name| f.call1(&JsValue::NULL, &name));
                if let Err(e) = called {
                    callback_error = Some(e);
                }
            }
        };
        let r = self.inner.register_owned_with_progress(source, target, &options, &mut progress).map_err(js_err)?;
        if let Some(e) = callback_error {
            return Err(JsError::new(&format!("onProgress threw: {}", js_message(&e))));
        }
        to_js(&r)
    }

    /// Drops the target kept from the last registration (a registration onto the same points
    /// reuses it; see the core's `Registrar`), so that the next one prepares its target anew.
    /// WebAssembly memory is not given back to the page, but the engine reuses it.
    #[wasm_bindgen(js_name = forgetTarget)]
    pub fn forget_target(&mut self) {
        self.inner.forget_target();
    }

    /// How the loaded weights were made (the weights file's provenance JSON), e.g.
    /// `{ kind: "random", seed: 0 }` for untrained placeholder weights.
    #[wasm_bindgen(getter, unchecked_return_type = "ModelProvenance")]
    pub fn provenance(&self) -> Result<JsValue, JsError> {
        to_js(self.inner.provenance())
    }

    /// The network configuration of the loaded weights (sizes, preset name): the core's
    /// `ModelConfig` with camelCase keys (`nPoints`, `featureDim`, ...), like the rest of the JS
    /// API (the weights file stores them in snake_case).
    #[wasm_bindgen(getter, js_name = modelConfig, unchecked_return_type = "ModelConfig")]
    pub fn model_config(&self) -> Result<JsValue, JsError> {
        to_js(&crate::contract::model_config_json(&self.inner.model().config))
    }
}

/// Core error whose message is prefixed with which argument it concerns.
fn prefixed(what: &str, e: crate::Error) -> JsError {
    JsError::new(&format!("{what}: {e}"))
}

fn set(obj: &Object, key: &str, value: &JsValue) -> Result<(), JsError> {
    Reflect::set(obj, &JsValue::from_str(key), value)
        .map(|_| ())
        .map_err(|_| JsError::new(&format!("internal: could not set result field {key}")))
}

/// Serialises with plain JS objects for maps (not `Map`s).
fn to_js<T: serde::Serialize + ?Sized>(value: &T) -> Result<JsValue, JsError> {
    let ser = serde_wasm_bindgen::Serializer::new().serialize_maps_as_objects(true);
    value.serialize(&ser).map_err(|e| JsError::new(&format!("internal: {e}")))
}

/// JS options object -> core [`Options`] ([`parse_object`]).
fn parse_options(options: JsValue) -> Result<Options, JsError> {
    parse_object(options, "options")
}

/// JS options object -> a core serde struct `T` (`what` names it in errors: "invalid {what}: ...").
/// `undefined`/`null` give the defaults; missing fields take their defaults; unknown fields and
/// wrong types throw. Values are read by the core's serde types (`initialTransform`:
/// [`crate::contract::initial_transform`]; typed arrays are copied to plain arrays first).
fn parse_object<T: serde::de::DeserializeOwned + Default>(options: JsValue, what: &str) -> Result<T, JsError> {
    if options.is_undefined() || options.is_null() {
        return Ok(T::default());
    }
    if !options.is_object() || Array::is_array(&options) {
        return Err(JsError::new(&format!("invalid {what}: expected a plain object (or undefined)")));
    }
    // A clean copy (the caller's object is never modified) holding only the fields that are
    // given: `undefined` and `null` mean "not given", so the default applies (serde-wasm-bindgen
    // would reject `seed: undefined`). serde-wasm-bindgen reads a struct by asking for each known
    // field, so it never sees unknown ones and `deny_unknown_fields` has no effect: unknown keys
    // are rejected here, against the core's own field list (taken from its `Deserialize` impl,
    // so it cannot drift).
    let fields = struct_fields::<T>();
    let clean = Object::new();
    // Every read of the caller's object may run a getter or a Proxy trap: each goes through a
    // `catch` import, so a throw becomes this call's error instead of unwinding through wasm.
    let keys = object_keys(&options)
        .map_err(|e| JsError::new(&format!("invalid {what}: listing them threw: {}", js_message(&e))))?;
    for key in keys.iter() {
        let name = key.as_string().unwrap_or_default();
        let value = Reflect::get(&options, &key)
            .map_err(|e| JsError::new(&format!("invalid {what}: reading `{name}` threw: {}", js_message(&e))))?;
        if value.is_undefined() || value.is_null() {
            continue;
        }
        if !fields.contains(&name.as_str()) {
            return Err(JsError::new(&format!(
                "invalid {what}: unknown field `{name}`, expected one of {}",
                fields.iter().map(|f| format!("`{f}`")).collect::<Vec<_>>().join(", ")
            )));
        }
        // A typed array (a 4x4 as `Float32Array`/`Float64Array`) as a plain `Array`: serde reads
        // untagged layouts (`initialTransform`) through `deserialize_any`, which sees only `Array`s.
        let value = if value.is_instance_of::<Float32Array>() || value.is_instance_of::<js_sys::Float64Array>() {
            Array::from(&value).into()
        } else {
            value
        };
        Reflect::set(&clean, &key, &value)
            .map_err(|_| JsError::new(&format!("internal: could not copy option {name}")))?;
    }
    serde_wasm_bindgen::from_value::<T>(clean.clone().into()).map_err(|e| {
        // serde names the value but not its field: the field is the first that fails alone
        let message = e.to_string();
        let message = message.strip_prefix("Error: ").unwrap_or(&message);
        let message = readable_serde_message(message);
        // the error of `T` from an object of one field, if any
        let fails = |one: JsValue| serde_wasm_bindgen::from_value::<T>(one).err().map(|e| e.to_string());
        let alone = |key: &JsValue| {
            let one = Object::new();
            Reflect::set(&one, key, &Reflect::get(&clean, key).unwrap_or(JsValue::UNDEFINED)).is_ok()
                && fails(one.into()).is_some()
        };
        match object_keys(&clean).ok().and_then(|keys| keys.iter().find(alone)).and_then(|k| k.as_string()) {
            Some(field) => {
                let message = with_choices(message, &field, &fails);
                JsError::new(&format!("invalid {what}: `{field}`: {message}"))
            }
            None => JsError::new(&format!("invalid {what}: {message}")),
        }
    })
}

/// `message` about `field`, where it names the Rust type of a named choice (`expected enum
/// IcpLoss`, a value of the wrong type), with the choices instead, as serde lists them for a name
/// that is none of them (`fails`: the error of an object of that one field, if any).
fn with_choices(message: String, field: &str, fails: &dyn Fn(JsValue) -> Option<String>) -> String {
    let Some(at) = message.find(", expected enum ") else { return message };
    let choices = |probe: JsValue| {
        let one = Object::new();
        Reflect::set(&one, &JsValue::from_str(field), &probe).ok()?;
        let e = fails(one.into())?;
        e.split_once("unknown variant ``, ").map(|(_, expected)| expected.to_string())
    };
    // a choice, or a list of them (`starts`)
    match choices(JsValue::from_str("")).or_else(|| choices(Array::of1(&"".into()).into())) {
        Some(expected) => format!("{}, {expected}", &message[..at]),
        None => message,
    }
}

/// serde-wasm-bindgen's message in the contract's words: its integer and float types, the
/// `JsValue(...)` it names a value by, the `TypeError` it meets where a list was expected (a
/// string given for `up` or `starts`), and a hint for whole numbers from 2^53 on (a `bigint`).
fn readable_serde_message(message: &str) -> String {
    let whole = "expected a whole number, 0 or more";
    // (`usize` is 32 bits here: 2^32 does not fit a point count any more than an iteration cap)
    let small = "expected a whole number from 0 to 4294967295";
    let mut m = message
        .replace("expected u64", whole)
        .replace("expected u32", small)
        .replace("expected usize", small)
        .replace("expected f64", "expected a number")
        .replace("TypeError: Reflect.get called on non-object", "invalid type: expected a list")
        .replace(
            "Couldn't deserialize u64 from a BigInt outside u64::MIN..u64::MAX bounds",
            "invalid value: a bigint beyond 0..=18446744073709551615 (2^64 - 1), expected a whole number in that range",
        )
        .replace(
            "Couldn't deserialize u32 from a BigInt outside u32::MIN..u32::MAX bounds",
            "invalid value: a bigint beyond 0..=4294967295, expected a whole number in that range",
        );
    // `JsValue([1])` -> `[1]`
    while let Some(at) = m.find("JsValue(") {
        let inner_start = at + "JsValue(".len();
        // its closing parenthesis (the value may hold others)
        let mut depth = 1usize;
        let close = m[inner_start..].char_indices().find(|&(_, c)| {
            match c {
                '(' => depth += 1,
                ')' => depth -= 1,
                _ => {}
            }
            depth == 0
        });
        let Some(end) = close.map(|(e, _)| inner_start + e) else { break };
        let inner = m[inner_start..end].to_string();
        m.replace_range(at..=end, &inner);
    }
    // a float of many digits (1e300 as serde writes it: 301 of them) in its short form
    if let Some(at) = m.find("floating point `") {
        let start = at + "floating point `".len();
        if let Some(len) = m[start..].find('`') {
            let text = &m[start..start + len];
            if let Ok(v) = text.parse::<f64>() {
                if text.len() > 24 {
                    let short = format!("{v:e}");
                    m.replace_range(start..start + len, &short);
                }
            }
        }
    }
    for expected in [whole, small] {
        if !m.contains(expected) {
            continue;
        }
        let value = m.split('`').nth(1).and_then(|v| v.parse::<f64>().ok());
        // a float that is a whole number from 2^53 on: JS numbers cannot hold such seeds exactly
        if expected == whole && value.is_some_and(|v| v >= 9_007_199_254_740_992.0) {
            m.push_str(" (from 2^53 on, give it as a bigint: 2n ** 53n)");
        }
        // a negative whole number reaches serde as a float: say what is wrong with it, its sign
        if let Some(v) = value.filter(|v| *v < 0.0 && v.fract() == 0.0) {
            m = format!("invalid value: {v}, {expected}");
        }
    }
    m
}

/// The (renamed) field names of a `Deserialize` struct: serde's derive passes them to
/// `Deserializer::deserialize_struct`, which this deserializer records and then stops.
fn struct_fields<T: serde::de::DeserializeOwned>() -> &'static [&'static str] {
    use serde::de::{self, Visitor};
    struct Capture<'a>(&'a mut &'static [&'static str]);
    impl<'de> de::Deserializer<'de> for Capture<'_> {
        type Error = de::value::Error;
        fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, Self::Error> {
            Err(de::Error::custom("not a struct"))
        }
        fn deserialize_struct<V: Visitor<'de>>(
            self,
            _name: &'static str,
            fields: &'static [&'static str],
            _visitor: V,
        ) -> Result<V::Value, Self::Error> {
            *self.0 = fields;
            Err(de::Error::custom("fields captured"))
        }
        serde::forward_to_deserialize_any! {
            bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
            option unit unit_struct newtype_struct seq tuple tuple_struct map enum identifier
            ignored_any
        }
    }
    let mut fields: &'static [&'static str] = &[];
    let _ = T::deserialize(Capture(&mut fields));
    fields
}
