//! `arps bench`: per-stage timings of the pipeline and the network's GFLOP/s against the matmul peak,
//! measured in the same run. Figures are medians over `--reps` repetitions.

use arps::{io, nn, transform, IcpKind, Options, PointCloud};
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args)]
pub struct BenchArgs {
    /// Weights file (default: the embedded model).
    #[arg(long)]
    weights: Option<PathBuf>,
    /// Source cloud file (default: a synthetic 1024-point partial view).
    #[arg(long, requires = "target")]
    source: Option<PathBuf>,
    /// Target cloud file.
    #[arg(long, requires = "source")]
    target: Option<PathBuf>,
    /// Points per synthetic cloud.
    #[arg(long, default_value_t = 1024)]
    points: usize,
    /// Repetitions (medians are reported).
    #[arg(long, default_value_t = 15)]
    reps: usize,
    /// Refinement.
    #[arg(long, default_value = "plane")]
    icp: String,
}

/// The median of `v` (sorted in place; the mean of the middle two for an even count; 0 if empty).
pub(crate) fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return 0.0;
    }
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// A deterministic synthetic pair: two overlapping partial views of a bumpy closed surface, the
/// target moved by a known 20-degree rotation and a translation.
fn synthetic_pair(n: usize) -> (PointCloud, PointCloud, nalgebra::Matrix4<f64>) {
    let surface = |u: f64, v: f64| {
        // a torus with bumps, in roughly [-1, 1]^3
        let r = 0.3 + 0.05 * (5.0 * u).sin() * (3.0 * v).cos();
        let big = 0.65;
        [(big + r * v.cos()) * u.cos(), (big + r * v.cos()) * u.sin(), r * v.sin() * 1.4]
    };
    let view = |n: usize, phase: f64| -> PointCloud {
        let mut pts = Vec::with_capacity(n);
        let mut i = 0u64;
        while pts.len() < n {
            // low-discrepancy (R2 sequence) parameters
            let a = (0.5 + i as f64 * 0.754_877_666_246_692_7) % 1.0;
            let b = (0.5 + i as f64 * 0.569_840_290_998_053_3) % 1.0;
            i += 1;
            let u = a * std::f64::consts::TAU;
            let v = b * std::f64::consts::TAU;
            // keep a 75% arc of the ring: a partial view
            if ((u - phase).rem_euclid(std::f64::consts::TAU)) > 0.75 * std::f64::consts::TAU {
                continue;
            }
            let p = surface(u, v);
            pts.push([p[0] as f32, p[1] as f32, p[2] as f32]);
        }
        PointCloud::new(pts)
    };
    let source = view(n, 0.0);
    let t = transform::from_rotation_translation(
        &transform::euler_xyz(0.2, -0.25, 0.15),
        &nalgebra::Vector3::new(0.1, -0.05, 0.08),
    );
    let target = view(n, 1.0).transformed(&t);
    (source, target, t)
}

/// sgemm GFLOP/s for `[m,k] x [k,n]`, median of `reps`.
fn matmul_gflops(m: usize, k: usize, n: usize, reps: usize) -> f64 {
    let a: Vec<f32> = (0..m * k).map(|i| ((i * 7919) % 1000) as f32 * 1e-3).collect();
    let b: Vec<f32> = (0..k * n).map(|i| ((i * 104_729) % 1000) as f32 * 1e-3).collect();
    let mut c = vec![0.0f32; m * n];
    nn::matmul(&a, &b, &mut c, m, k, n); // warm-up
    let mut times: Vec<f64> = (0..reps)
        .map(|_| {
            let t = Instant::now();
            nn::matmul(&a, &b, &mut c, m, k, n);
            t.elapsed().as_secs_f64()
        })
        .collect();
    std::hint::black_box(&c);
    2.0 * (m * k * n) as f64 / median(&mut times) / 1e9
}

pub fn run(args: BenchArgs) -> Result<(), String> {
    let mut registrar = crate::load_registrar(args.weights.as_deref())?;
    let (source, target, truth) = match (&args.source, &args.target) {
        (Some(s), Some(t)) => (
            io::read_path(s).map_err(|e| format!("{}: {e}", s.display()))?,
            io::read_path(t).map_err(|e| format!("{}: {e}", t.display()))?,
            None,
        ),
        _ => {
            let (s, t, m) = synthetic_pair(args.points);
            (s, t, Some(m))
        }
    };
    let icp = match args.icp.as_str() {
        "plane" => IcpKind::Plane,
        "point" => IcpKind::Point,
        "off" => IcpKind::Off,
        other => return Err(format!("--icp {other}: expected plane, point or off")),
    };
    let reps = args.reps.max(1);
    // Read stage: parse both clouds from binary PLY bytes in memory.
    let bytes = [io::write_ply_binary(&source), io::write_ply_binary(&target)];
    let mut read_ms: Vec<f64> = (0..reps)
        .map(|_| {
            let t = Instant::now();
            for b in &bytes {
                std::hint::black_box(io::read_point_cloud(b, "cloud.ply").expect("own PLY output parses"));
            }
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    let options = Options { icp, ..Options::default() };
    let _ = registrar.register(&source, &target, &options).map_err(|e| e.to_string())?; // warm-up
    let mut stages: [Vec<f64>; 5] = Default::default();
    let mut last = None;
    for _ in 0..reps {
        // each repetition prepares the target, as a call onto a new target does
        registrar.forget_target();
        let r = registrar.register(&source, &target, &options).map_err(|e| e.to_string())?;
        let t = r.timings;
        for (v, x) in stages.iter_mut().zip([t.preprocess_ms, t.network_ms, t.gmr_ms, t.icp_ms, t.total_ms]) {
            v.push(x);
        }
        last = Some(r);
    }
    let r = last.expect("reps >= 1");
    let [mut pre, mut net, mut gmr, mut icp_t, mut total] = stages;
    let cfg = &registrar.model().config;
    let n_net = cfg.n_points;
    let flops = registrar.model().flops(n_net, n_net) as f64;
    let net_ms = median(&mut net);
    let net_gflops = flops / (net_ms * 1e-3) / 1e9;
    let peak_square = matmul_gflops(512, 512, 512, 9);
    let peak_model = matmul_gflops(n_net, cfg.token_dim(), cfg.token_dim(), 15);
    let peak = peak_square.max(peak_model);

    out!(
        "arps bench: {} + {} points, model '{}' (N = {n_net}, C = {}, L = {}), ICP {:?}, {reps} reps, medians",
        source.len(),
        target.len(),
        cfg.preset,
        cfg.feature_dim,
        cfg.layers,
        icp
    );
    out!("  read (2 x binary PLY)   {:>9.3} ms", median(&mut read_ms));
    out!("  downsample/normalise    {:>9.3} ms", median(&mut pre));
    out!("  network                 {:>9.3} ms   ({:.2} GFLOP per pair)", net_ms, flops / 1e9);
    out!("  GMR                     {:>9.3} ms", median(&mut gmr));
    out!(
        "  ICP                     {:>9.3} ms   ({} starts; chosen: {}, {} iterations)",
        median(&mut icp_t),
        options.starts.len(),
        r.start.name(),
        r.icp_iterations
    );
    out!("  total register()        {:>9.3} ms", median(&mut total));
    out!("  network throughput      {:>9.1} GFLOP/s", net_gflops);
    out!(
        "  matmul peak             {:>9.1} GFLOP/s   (512^3: {:.1}; [{n_net} x {d}] x [{d} x {d}]: {:.1})",
        peak,
        peak_square,
        peak_model,
        d = cfg.token_dim()
    );
    out!("  network / peak          {:>9.2}", net_gflops / peak);
    if let Some(truth) = truth {
        out!(
            "  accuracy (synthetic pair): rotation error {:.3} deg, translation error {:.4}; network only {:.2} deg, {:.4}",
            transform::rotation_error_deg(&r.T_target_source, &truth),
            transform::translation_error(&r.T_target_source, &truth),
            transform::rotation_error_deg(&r.T_target_source_network, &truth),
            transform::translation_error(&r.T_target_source_network, &truth),
        );
    }
    Ok(())
}
