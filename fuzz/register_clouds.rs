// The body of the `register_clouds` fuzz target (`fuzz_targets/register_clouds.rs`), included
// there and by `tests/io_fuzz_regressions.rs`, which replays the seeds and every input found
// crashing. See the target's docs for the input's layout.

/// The points of `bytes` (three signed bytes each), each grown into `copies` points spread by
/// `spread` grid steps (a fixed pattern, so duplicates stay duplicates when `spread` is 0).
fn grid_points(bytes: &[u8], copies: usize, spread: f64) -> Vec<[f64; 3]> {
    let mut out = Vec::new();
    for p in bytes.chunks_exact(3) {
        let base = [p[0] as i8 as f64, p[1] as i8 as f64, p[2] as i8 as f64];
        for c in 0..copies {
            let k = c as f64;
            let jitter = [(k * 0.618_034) % 1.0, (k * 0.414_214) % 1.0, (k * 0.732_051) % 1.0];
            out.push([0, 1, 2].map(|a| base[a] + spread * (jitter[a] - 0.5)));
        }
    }
    out
}

/// `points` scaled by `scale`, moved by `offset`, as a cloud (through the `f64` constructor, as a
/// reader of georeferenced data does).
fn cloud(points: &[[f64; 3]], scale: f64, offset: f64) -> Option<arps::PointCloud> {
    let flat: Vec<f64> = points.iter().flat_map(|p| p.map(|v| v * scale + offset)).collect();
    arps::PointCloud::from_xyz_f64(&flat).ok()
}

/// `p` turned by the Euler angles `(angle, 2 angle, 3 angle)` ([`arps::transform::euler_xyz`]).
fn turn(p: [f64; 3], angle: f64) -> [f64; 3] {
    let r = arps::transform::euler_xyz(angle, 2.0 * angle, 3.0 * angle);
    [0, 1, 2].map(|i| (0..3).map(|j| r[(i, j)] * p[j]).sum())
}

fn check(r: &arps::Registration) {
    assert!(r.T_target_source.iter().all(|v| v.is_finite()), "{:?}", r.T_target_source);
    arps::transform::check_rigid(&r.T_target_source, 1e-3).expect("a rigid answer");
    assert!((0.0..=1.0).contains(&r.fitness), "fitness {}", r.fitness);
    assert!((0.0..=1.0).contains(&r.confidence), "confidence {}", r.confidence);
    assert!(r.inlier_rmse.is_finite() && r.inlier_rmse >= 0.0, "inlier RMSE {}", r.inlier_rmse);
    assert!(r.max_correspondence_distance.is_finite() && r.max_correspondence_distance > 0.0);
    for a in &r.alternatives {
        assert!(a.T_target_source.iter().all(|v| v.is_finite()));
        arps::transform::check_rigid(&a.T_target_source, 1e-3).expect("a rigid alternative");
        assert!((0.0..=1.0).contains(&a.fitness), "alternative's fitness {}", a.fitness);
    }
}

/// The pair that `data` describes (see the target's docs): source, target, the options, and
/// whether to check that a second registration gives the same answer. `None` for too few bytes or
/// coordinates out of range.
fn pair_of(data: &[u8]) -> Option<(arps::PointCloud, arps::PointCloud, arps::Options, bool)> {
    if data.len() < 6 {
        return None;
    }
    let (head, body) = data.split_at(6);
    let flag = |b: u8| head[0] & (1 << b) != 0;
    let copies = 1 + (head[1] & 15) as usize;
    let spread = (head[1] >> 4) as f64 / 4.0;
    let exponent = |b: u8| ((b as i8) / 10).clamp(-12, 12);
    let (source_scale, target_scale) = (10f64.powi(exponent(head[2]) as i32), 10f64.powi(exponent(head[3]) as i32));
    let offset = if flag(6) { 5.0e6 } else { 0.0 };

    let split = (body.len() / 3 * head[4] as usize / 255) * 3;
    let target_points = grid_points(&body[..split], copies, spread);
    let source_points = if flag(5) {
        // part of the target, turned: a pair that has an answer
        let keep = 1 + target_points.len() * (1 + (head[5] & 15) as usize) / 16;
        let angle = (head[5] >> 4) as f64 / 16.0 * std::f64::consts::TAU;
        target_points.iter().take(keep).map(|&p| turn(p, angle)).collect()
    } else {
        grid_points(&body[split..], copies, spread)
    };
    let target = cloud(&target_points, target_scale, offset)?;
    let source = cloud(&source_points, if flag(5) { target_scale } else { source_scale }, offset)?;

    let options = arps::Options {
        up: flag(0).then_some([0.0, 0.0, 1.0]),
        support_plane: if flag(1) { arps::Support::Keep } else { arps::Support::Drop },
        outliers: if flag(2) { arps::Outliers::Keep } else { arps::Outliers::Drop },
        icp: if flag(3) { arps::IcpKind::Point } else { arps::IcpKind::Plane },
        search: if flag(4) { arps::Search::Exhaustive } else { arps::Search::Adaptive },
        icp_max_iterations: 10,
        ..arps::Options::default()
    };
    Some((source, target, options, flag(7)))
}

/// Registers the pair that `data` describes with `reg` ([`pair_of`]) and checks the answer (see
/// the target's docs); panics when a check fails. True when the pair gave an answer (not an
/// error, nor too few bytes).
fn register_clouds_target(reg: &mut arps::Registrar, data: &[u8]) -> bool {
    let Some((source, target, options, twice)) = pair_of(data) else { return false };
    match reg.register(&source, &target, &options) {
        Ok(r) => {
            check(&r);
            if twice {
                let again = reg.register(&source, &target, &options).expect("the same answer again");
                assert_eq!(r.T_target_source, again.T_target_source, "same input, same output");
                assert_eq!(r.confidence.to_bits(), again.confidence.to_bits(), "same input, same confidence");
            }
            true
        }
        Err(_) => {
            // still usable
            let s = arps::PointCloud::new(
                (0..64).map(|i| [(i % 4) as f32, (i / 4 % 4) as f32, (i / 16) as f32 * 0.7]).collect(),
            );
            let r = reg.register(&s, &s, &arps::Options { icp_max_iterations: 5, ..arps::Options::default() });
            check(&r.expect("usable after an error"));
            false
        }
    }
}
