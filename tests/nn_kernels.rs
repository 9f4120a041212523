//! Every fast kernel of `arps::nn` against its naive reference in `arps::nn::reference`.
//!
//! Tolerance: `|got - want| <= RTOL * (|want| + rms(want))`, RTOL = 1e-5 (f32 accumulation in a
//! different order than the f64 reference, plus the fast exp's ~2e-7 relative error).

use arps::nn::gemm::{gemm_blocked_with, Kernel};
use arps::nn::{self, reference as r, AttentionBlock, LayerNorm, Linear, Mlp, MultiHeadAttention, Workspace};

const RTOL: f32 = 1e-5;
const SIZES: [usize; 6] = [1, 3, 7, 17, 64, 129];

struct Rng(u64);
impl Rng {
    fn f(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        ((self.0 >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }
    fn vec(&mut self, n: usize, s: f32) -> Vec<f32> {
        (0..n).map(|_| self.f() * s).collect()
    }
}

#[track_caller]
fn assert_close(got: &[f32], want: &[f32], rtol: f32, what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: length");
    let rms = (want.iter().map(|v| (*v as f64).powi(2)).sum::<f64>() / want.len().max(1) as f64).sqrt() as f32;
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        let tol = rtol * (w.abs() + rms);
        assert!((g - w).abs() <= tol, "{what}: [{i}] got {g}, want {w} (tol {tol})");
    }
}

fn linear(rng: &mut Rng, i: usize, o: usize, bias: bool) -> Linear {
    Linear {
        weight: rng.vec(i * o, 1.0 / (i as f32).sqrt()),
        bias: bias.then(|| rng.vec(o, 0.2)),
        in_dim: i,
        out_dim: o,
        quant: None,
    }
}

fn layernorm(rng: &mut Rng, d: usize) -> LayerNorm {
    LayerNorm { gamma: rng.vec(d, 0.2).into_iter().map(|v| 1.0 + v).collect(), beta: rng.vec(d, 0.2), eps: 1e-5 }
}

fn block(rng: &mut Rng, d: usize, heads: usize, ffn: usize) -> AttentionBlock {
    AttentionBlock {
        attn: MultiHeadAttention {
            q: linear(rng, d, d, true),
            k: linear(rng, d, d, true),
            v: linear(rng, d, d, true),
            o: linear(rng, d, d, true),
            heads,
        },
        norm1: layernorm(rng, d),
        ffn1: linear(rng, d, ffn, true),
        ffn2: linear(rng, ffn, d, true),
        norm2: layernorm(rng, d),
    }
}

#[test]
fn matmul_and_matmul_bt_match_reference() {
    let mut rng = Rng(1);
    for &m in &SIZES {
        for &k in &SIZES {
            for &n in &SIZES {
                let a = rng.vec(m * k, 1.0);
                let b = rng.vec(k * n, 1.0);
                let mut c = vec![f32::NAN; m * n];
                nn::matmul(&a, &b, &mut c, m, k, n);
                assert_close(&c, &r::matmul(&a, &b, m, k, n), RTOL, &format!("matmul {m}x{k}x{n}"));
                c.fill(f32::NAN);
                nn::matmul_bt(&a, &b, &mut c, m, k, n);
                assert_close(&c, &r::matmul_bt(&a, &b, m, k, n), RTOL, &format!("matmul_bt {m}x{k}x{n}"));
            }
        }
    }
}

type GemmFn =
    dyn Fn(usize, usize, usize, f32, &[f32], isize, isize, &[f32], isize, isize, f32, &mut [f32], isize, isize);

/// Strided cases: transposed operands, padded row strides, a column-strided C, alpha/beta,
/// beta = 0 over a NaN-filled C, k = 0, and shapes crossing the blocked GEMM's KC/MC/NC.
fn check_strided(f: &GemmFn, name: &str) {
    let mut rng = Rng(2);
    let shapes = [
        (1, 1, 1),
        (3, 7, 17),
        (17, 3, 7),
        (64, 129, 7),
        (129, 17, 64),
        (7, 300, 33),
        (70, 260, 520),
        (9, 20, 1030),
        (5, 0, 9),
    ];
    for &(m, k, n) in &shapes {
        for layout in 0..9 {
            // A: row-major with padding, transposed (column-major with padding), or with both
            // strides > 1 (every second column); B likewise.
            let (rsa, csa, alen) = match layout % 3 {
                0 => (k as isize + 3, 1, m * (k + 3)),
                1 => (1, m as isize + 2, (m + 2) * k.max(1)),
                _ => (2 * k as isize + 1, 2, m * (2 * k + 1)),
            };
            let (rsb, csb, blen) = match layout / 3 {
                0 => (n as isize + 1, 1, k * (n + 1)),
                1 => (1, k as isize + 5, (k + 5) * n),
                _ => (2 * n as isize + 3, 2, k * (2 * n + 3)),
            };
            let a = rng.vec(alen.max(1), 1.0);
            let b = rng.vec(blen.max(1), 1.0);
            // C: every second column of a wider buffer.
            let (rsc, csc) = (2 * n as isize + 1, 2);
            let c0 = rng.vec(m * (2 * n + 1), 1.0);
            for (alpha, beta) in [(1.0, 0.0), (0.7, 0.3), (-1.5, 1.0)] {
                let mut want = c0.clone();
                r::gemm(m, k, n, alpha, &a, rsa, csa, &b, rsb, csb, beta, &mut want, rsc, csc);
                let mut got = c0.clone();
                if beta == 0.0 {
                    // beta = 0 must not read C: poison the written elements.
                    for i in 0..m {
                        for j in 0..n {
                            got[i * rsc as usize + j * csc as usize] = f32::NAN;
                        }
                    }
                }
                f(m, k, n, alpha, &a, rsa, csa, &b, rsb, csb, beta, &mut got, rsc, csc);
                assert_close(
                    &got,
                    &want,
                    RTOL,
                    &format!("{name} {m}x{k}x{n} layout {layout} alpha {alpha} beta {beta}"),
                );
            }
        }
    }
}

#[test]
fn gemm_strided_matches_reference() {
    check_strided(&nn::gemm, "gemm");
    check_strided(&nn::matmul::gemm_matrixmultiply, "gemm_matrixmultiply");
}

#[test]
fn blocked_gemm_matches_reference() {
    for kernel in [Kernel::Portable, Kernel::Simd128] {
        let f = move |m, k, n, al, a: &[f32], rsa, csa, b: &[f32], rsb, csb, be, c: &mut [f32], rsc, csc| {
            gemm_blocked_with(kernel, m, k, n, al, a, rsa, csa, b, rsb, csb, be, c, rsc, csc)
        };
        check_strided(&f, &format!("{kernel:?}"));
        let mut rng = Rng(3);
        for &m in &SIZES {
            for &n in &SIZES {
                for k in [1, 17, 129, 257] {
                    let a = rng.vec(m * k, 1.0);
                    let b = rng.vec(n * k, 1.0);
                    let mut c = vec![f32::NAN; m * n];
                    f(m, k, n, 1.0, &a, k as isize, 1, &b, 1, k as isize, 0.0, &mut c, n as isize, 1);
                    assert_close(&c, &r::matmul_bt(&a, &b, m, k, n), RTOL, &format!("{kernel:?} bt {m}x{k}x{n}"));
                }
            }
        }
    }
}

#[test]
#[should_panic(expected = "too short")]
fn gemm_rejects_short_slices() {
    let a = vec![0.0; 5];
    let b = vec![0.0; 6];
    let mut c = vec![0.0; 4];
    nn::matmul(&a, &b, &mut c, 2, 3, 2);
}

#[test]
fn linear_and_mlp_match_reference() {
    let mut rng = Rng(4);
    for &rows in &SIZES {
        for &(i, o) in &[(1, 1), (3, 7), (17, 64), (129, 3), (128, 256)] {
            for bias in [false, true] {
                let l = linear(&mut rng, i, o, bias);
                let x = rng.vec(rows * i, 1.0);
                let mut y = vec![f32::NAN; rows * o];
                l.forward(&x, rows, &mut y);
                let want = r::linear(&l, &x, rows);
                assert_close(&y, &want, RTOL, &format!("linear {rows}x{i}->{o} bias {bias}"));
                let mut yt = vec![f32::NAN; rows * o];
                l.forward_transposed(&x, rows, &mut yt);
                let want_t: Vec<f32> = (0..o * rows).map(|t| want[(t % rows) * o + t / rows]).collect();
                assert_close(&yt, &want_t, RTOL, &format!("linear^T {rows}x{i}->{o} bias {bias}"));
            }
        }
        for (dims, relu_last) in [(&[3usize, 17][..], true), (&[3, 64, 128][..], true), (&[7, 33, 5, 2][..], false)] {
            let mlp = Mlp { layers: dims.windows(2).map(|w| linear(&mut rng, w[0], w[1], true)).collect(), relu_last };
            let x = rng.vec(rows * dims[0], 1.0);
            let mut y = vec![f32::NAN; rows * mlp.out_dim()];
            mlp.forward(&x, rows, &mut y, &mut Vec::new(), &mut Vec::new());
            assert_close(&y, &r::mlp(&mlp, &x, rows), RTOL, &format!("mlp {dims:?} rows {rows}"));
        }
    }
}

#[test]
fn layernorm_matches_reference() {
    let mut rng = Rng(5);
    for &rows in &SIZES {
        for &d in &SIZES {
            let ln = layernorm(&mut rng, d);
            // Offset rows (mean far from 0) as well as centred ones.
            let x: Vec<f32> = rng
                .vec(rows * d, 2.0)
                .iter()
                .enumerate()
                .map(|(i, v)| v + if i % 3 == 0 { 100.0 } else { 0.0 })
                .collect();
            let mut y = x.clone();
            ln.forward_inplace(&mut y);
            assert_close(&y, &r::layernorm(&ln, &x), 2e-5, &format!("layernorm {rows}x{d}"));
            let res = rng.vec(rows * d, 1.0);
            let mut y = x.clone();
            ln.forward_residual_inplace(&mut y, &res);
            let sum: Vec<f32> = x.iter().zip(&res).map(|(a, b)| a + b).collect();
            assert_close(&y, &r::layernorm(&ln, &sum), 2e-5, &format!("layernorm+residual {rows}x{d}"));
        }
    }
}

#[test]
fn layernorm_of_constant_row_is_beta() {
    let mut rng = Rng(6);
    for d in [1, 7, 128, 129] {
        let ln = layernorm(&mut rng, d);
        for c in [0.0f32, 0.1, -3.7, 1e6] {
            let mut x = vec![c; 2 * d];
            ln.forward_inplace(&mut x);
            assert_eq!(&x[..d], &ln.beta[..], "d = {d}, c = {c}");
            assert_eq!(&x[d..], &ln.beta[..], "d = {d}, c = {c}");
        }
    }
}

#[test]
fn softmax_matches_reference() {
    let mut rng = Rng(7);
    for &rows in &SIZES {
        for &cols in &[1, 3, 7, 17, 64, 129, 1000] {
            for scale in [1.0, 10.0, 80.0] {
                let x = rng.vec(rows * cols, scale);
                let mut y = x.clone();
                nn::softmax_rows_inplace(&mut y, cols);
                assert_close(&y, &r::softmax_rows(&x, cols), RTOL, &format!("softmax {rows}x{cols} scale {scale}"));
            }
        }
    }
}

#[test]
fn softmax_extreme_rows_are_finite_distributions() {
    let inf = f32::INFINITY;
    let rows: Vec<Vec<f32>> = vec![
        vec![-inf, 0.0, -inf, 1.0],
        vec![-inf; 5],
        vec![1e30, -1e30, 0.0, 1e30],
        vec![f32::MAX, f32::MIN, 0.0],
        vec![-1e30, -1e30 + 1e24, -1e30],
        vec![inf, 1.0, inf, -inf],
        vec![3.0],
        vec![-inf],
        (0..37).map(|i| if i % 5 == 0 { -inf } else { i as f32 * 1e3 }).collect(),
    ];
    for row in rows {
        let mut y = row.clone();
        nn::softmax_rows_inplace(&mut y, row.len());
        assert!(y.iter().all(|v| v.is_finite() && *v >= 0.0), "{row:?} -> {y:?}");
        let s: f32 = y.iter().sum();
        assert!((s - 1.0).abs() < 1e-6, "{row:?} sums to {s}");
        for (x, p) in row.iter().zip(&y) {
            if *x == -inf && row.iter().any(|v| *v > -inf) {
                assert_eq!(*p, 0.0, "{row:?} -> {y:?}");
            }
        }
    }
    let mut y = vec![-inf, 0.0, -inf, 1.0];
    nn::softmax_rows_inplace(&mut y, 4);
    assert_close(&y, &r::softmax_rows(&[-inf, 0.0, -inf, 1.0], 4), RTOL, "softmax with -inf");
    // cols = 0 is a no-op
    nn::softmax_rows_inplace(&mut [], 0);
}

#[test]
fn activations_match_reference() {
    let mut rng = Rng(8);
    let mut x = rng.vec(10_000, 12.0);
    x.extend([0.0, -0.0, 1e-20, -1e-20, 30.0, -30.0, 100.0, -100.0, 1e6, -1e6]);
    let mut g = x.clone();
    nn::gelu_inplace(&mut g);
    let want = r::gelu(&x);
    for (i, (a, b)) in g.iter().zip(&want).enumerate() {
        // The f32 rounding of the exponent argument 2z (~6e-8 relative) becomes a relative
        // error of ~6e-8 * |2z| in e^(-2z): the conditioning of any f32 evaluation.
        let u = x[i] as f64;
        let z2 = (2.0 * 0.797_884_6 * (u + 0.044715 * u * u * u)).abs().min(200.0) as f32;
        let tol = (4e-7 + 1.5e-7 * z2) * b.abs() + 1e-30;
        assert!((a - b).abs() <= tol, "gelu({}) = {a}, want {b}", x[i]);
    }
    let mut s = x.clone();
    nn::sigmoid_inplace(&mut s);
    let want = r::sigmoid(&x);
    for (i, (a, b)) in s.iter().zip(&want).enumerate() {
        assert!((a - b).abs() <= 1e-6 * b.abs() + 1e-37, "sigmoid({}) = {a}, want {b}", x[i]);
        assert_eq!(nn::sigmoid(x[i]), *a);
    }
    let mut y = x.clone();
    nn::relu_inplace(&mut y);
    assert_eq!(y, r::relu(&x));
}

#[test]
fn attention_matches_reference() {
    let mut rng = Rng(9);
    let mut ws = Workspace::default();
    for &(d, heads) in &[(8, 1), (8, 2), (16, 4), (128, 4)] {
        let mha = block(&mut rng, d, heads, 2 * d).attn;
        for &nq in &SIZES {
            for &nk in &[1, 5, 64, 130] {
                let xq = rng.vec(nq * d, 1.0);
                let xkv = rng.vec(nk * d, 1.0);
                let mut out = vec![f32::NAN; nq * d];
                mha.forward(&xq, nq, &xkv, nk, &mut out, &mut ws);
                assert_close(
                    &out,
                    &r::attention(&mha, &xq, nq, &xkv, nk),
                    RTOL,
                    &format!("mha d {d} h {heads} nq {nq} nk {nk}"),
                );
            }
        }
    }
}

#[test]
fn attention_core_with_peaked_scores() {
    // Large logits (nearly one-hot attention) exercise the exp's range.
    let mut rng = Rng(10);
    let (nq, nk, d, heads) = (70, 33, 16, 2);
    let q = rng.vec(nq * d, 6.0);
    let k = rng.vec(nk * d, 6.0);
    let v = rng.vec(nk * d, 1.0);
    let mut out = vec![0.0; nq * d];
    let mut scores = vec![0.0; nq * nk];
    nn::attention::attend(&q, nq, &k, &v, nk, d, heads, &mut out, &mut scores);
    let want = r::attend(&q, nq, &k, &v, nk, d, heads);
    assert_close(&out, &want, RTOL, "attend peaked");
    let kt: Vec<f32> = (0..d * nk).map(|t| k[(t % nk) * d + t / nk]).collect();
    out.fill(f32::NAN);
    nn::attention::attend_kt(&q, nq, &kt, &v, nk, d, heads, &mut out, &mut scores);
    assert_close(&out, &want, RTOL, "attend_kt peaked");
}

#[test]
fn attention_block_matches_reference() {
    let mut rng = Rng(11);
    let mut ws = Workspace::default();
    for &(d, heads, ffn) in &[(8, 2, 16), (16, 1, 32), (128, 4, 256)] {
        let b = block(&mut rng, d, heads, ffn);
        // Big sizes first so the workspace is reused at smaller ones.
        for &(nq, nk) in &[(129, 130), (64, 64), (7, 129), (129, 3), (1, 1), (17, 17)] {
            let x = rng.vec(nq * d, 1.0);
            let kv = rng.vec(nk * d, 1.0);
            let mut y = vec![f32::NAN; nq * d];
            b.forward(&x, nq, &kv, nk, &mut y, &mut ws);
            let want = r::attention_block(&b, &x, nq, &kv, nk);
            assert_close(&y, &want, 2e-5, &format!("block d {d} h {heads} nq {nq} nk {nk}"));
            // self-attention
            b.forward(&x, nq, &x, nq, &mut y, &mut ws);
            assert_close(&y, &r::attention_block(&b, &x, nq, &x, nq), 2e-5, &format!("self block d {d} nq {nq}"));
        }
    }
}

#[test]
fn flop_counts() {
    assert_eq!(nn::flops_linear(512, 128, 256), 2 * 512 * 128 * 256);
    let (n, d, f) = (512u64, 128u64, 256u64);
    let attn = 4 * 2 * n * d * d + 4 * n * n * d;
    assert_eq!(nn::flops_attention(512, 512, 128, 4), attn);
    assert_eq!(nn::flops_attention_block(512, 512, 128, 4, 256), attn + 4 * n * d * f);
    let mlp =
        Mlp { layers: vec![linear(&mut Rng(1), 3, 16, true), linear(&mut Rng(2), 16, 64, true)], relu_last: true };
    assert_eq!(nn::flops_mlp(&mlp, 10), 2 * 10 * (3 * 16 + 16 * 64));
}

fn now_ms() -> f64 {
    use std::sync::OnceLock;
    use std::time::Instant;
    static ORIGIN: OnceLock<Instant> = OnceLock::new();
    ORIGIN.get_or_init(Instant::now).elapsed().as_secs_f64() * 1e3
}

#[test]
fn matmul_bench_reports_a_rate() {
    let g = nn::bench_matmul_gflops(32, 3, now_ms);
    assert!(g.is_finite() && g > 0.0, "{g}");
}
