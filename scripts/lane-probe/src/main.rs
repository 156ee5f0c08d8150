//! Does lane-wise shading written once in plain Rust vectorise, and stay bit-identical
//! across widths? (docs/lanes.md, "Evidence".)
//!
//! One bounce's worth of typical lane work — two counter-based random numbers (the
//! core's `mix64` hash), a cosine-weighted direction (square root, a branch-free
//! polynomial sine and cosine), an orthonormal frame from a normal (Duff et al. 2017) and
//! the density — written once over `N` lanes in structure-of-arrays form, then compiled
//! four times: one lane at a time (the scalar reference), 16 lanes with the baseline
//! x86-64 features (SSE2), with AVX2 and with AVX-512, the latter two through
//! `#[target_feature]` and chosen only where the CPU reports them. LLVM vectorises the
//! lane loop by itself; Rust never fuses a multiply and an add, so every width must give
//! the scalar reference's bits (checked), and the printout is lane-bounces per second.
//!
//! The second line does the same bounce with the core's own functions in place of the
//! probe's f32 polynomial: `ember_core::math::sin_cos_turns` (f64 series, correctly
//! rounded) and `ember_core::math::sqrt`, called as they are, to show that the functions
//! the scalar renderer uses vectorise too and give the scalar bits at every width.

use std::time::Instant;

const W: usize = 16;

#[inline(always)]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[inline(always)]
fn to_unit(u: u64) -> f32 {
    ((u >> 40) as u32) as f32 * (1.0 / 16_777_216.0)
}

/// sin and cos on [−π, π] by odd and even polynomials (no branch, no table): one
/// implementation for every width.
#[inline(always)]
fn sincos(x: f32) -> (f32, f32) {
    let x2 = x * x;
    let s = x * (1.0 + x2 * (-0.166_666_67 + x2 * (0.008_333_331 + x2 * (-0.000_198_408_74 + x2 * (2.752_556_2e-6 + x2 * -2.388_985_9e-8)))));
    let c = 1.0 + x2 * (-0.5 + x2 * (0.041_666_638 + x2 * (-0.001_388_837_8 + x2 * (2.476_049_5e-5 + x2 * -2.605_161_5e-7))));
    (s, c)
}

/// The two functions a bounce needs, from the probe or from the core.
trait LaneMath {
    fn sqrt(x: f32) -> f32;
    /// sin and cos of the azimuth drawn from `u` ∈ [0, 1).
    fn azimuth(u: f32) -> (f32, f32);
}

/// The probe's f32 polynomial and std's square root.
struct Probe;

impl LaneMath for Probe {
    #[inline(always)]
    fn sqrt(x: f32) -> f32 {
        x.sqrt()
    }
    #[inline(always)]
    fn azimuth(u: f32) -> (f32, f32) {
        sincos((u - 0.5) * std::f32::consts::TAU)
    }
}

/// The core's own functions (issue 52): `sin_cos_turns` (f64 series, correctly rounded)
/// and `math::sqrt` (the `sqrtss` intrinsic), called as the renderer calls them.
struct Core;

impl LaneMath for Core {
    #[inline(always)]
    fn sqrt(x: f32) -> f32 {
        ember_core::math::sqrt(x)
    }
    #[inline(always)]
    fn azimuth(u: f32) -> (f32, f32) {
        ember_core::math::sin_cos_turns(u)
    }
}

/// The lane work for `N` lanes (see the module notes).
#[inline(always)]
fn bounce<const N: usize, M: LaneMath>(key: &[u64; N], dim: u32, n: &[[f32; N]; 3], out: &mut [[f32; N]; 4]) {
    for i in 0..N {
        let u1 = to_unit(mix64(key[i] ^ dim as u64));
        let u2 = to_unit(mix64(key[i] ^ (dim as u64 + 1)));
        let r = M::sqrt(u1);
        let (s, c) = M::azimuth(u2);
        let (x, y, z) = (r * c, r * s, M::sqrt((1.0 - u1).max(0.0)));
        let (nx, ny, nz) = (n[0][i], n[1][i], n[2][i]);
        let sign = 1.0f32.copysign(nz);
        let a = -1.0 / (sign + nz);
        let b = nx * ny * a;
        let t = (1.0 + sign * nx * nx * a, sign * b, -sign * nx);
        let bt = (b, sign + ny * ny * a, -ny);
        out[0][i] = x * t.0 + y * bt.0 + z * nx;
        out[1][i] = x * t.1 + y * bt.1 + z * ny;
        out[2][i] = x * t.2 + y * bt.2 + z * nz;
        out[3][i] = z * std::f32::consts::FRAC_1_PI;
    }
}

#[inline(never)]
fn one_lane<M: LaneMath>(key: &[u64; 1], dim: u32, n: &[[f32; 1]; 3], out: &mut [[f32; 1]; 4]) {
    bounce::<1, M>(key, dim, n, out)
}

#[inline(never)]
fn baseline<M: LaneMath>(key: &[u64; W], dim: u32, n: &[[f32; W]; 3], out: &mut [[f32; W]; 4]) {
    bounce::<W, M>(key, dim, n, out)
}

#[target_feature(enable = "avx2,fma")]
fn avx2<M: LaneMath>(key: &[u64; W], dim: u32, n: &[[f32; W]; 3], out: &mut [[f32; W]; 4]) {
    bounce::<W, M>(key, dim, n, out)
}

#[target_feature(enable = "avx512f,avx512dq,avx512vl")]
fn avx512<M: LaneMath>(key: &[u64; W], dim: u32, n: &[[f32; W]; 3], out: &mut [[f32; W]; 4]) {
    bounce::<W, M>(key, dim, n, out)
}

type Lanes = fn(&[u64; W], u32, &[[f32; W]; 3], &mut [[f32; W]; 4]);

fn main() {
    measure::<Probe>("the probe's f32 polynomial");
    measure::<Core>("the core's sin_cos_turns and sqrt");
}

#[allow(clippy::needless_range_loop, reason = "lanes indexed across several arrays")]
fn measure<M: LaneMath>(what: &str) {
    print!("{what}: ");

    let iters = 2_000_000u32;
    let key: [u64; W] = std::array::from_fn(|i| mix64(i as u64 + 1));
    let mut n = [[0.0f32; W]; 3];
    for i in 0..W {
        let a = i as f32 * 0.37;
        (n[0][i], n[1][i], n[2][i]) = (a.sin() * 0.6, a.cos() * 0.6, 0.8);
    }
    let lanes = (iters as f64) * W as f64;
    let mut check = 0.0f32;

    // The scalar reference: each lane through the one-lane build.
    let mut reference = [[0.0f32; W]; 4];
    let t = Instant::now();
    for d in 0..iters {
        for i in 0..W {
            let mut o = [[0.0f32; 1]; 4];
            one_lane::<M>(&[key[i]], d, &[[n[0][i]], [n[1][i]], [n[2][i]]], &mut o);
            (0..4).for_each(|k| reference[k][i] = o[k][0]);
        }
        check += reference[0][3];
    }
    let scalar = t.elapsed().as_secs_f64();
    print!("lane-bounces/s: scalar {:.0} M", lanes / scalar / 1e6);

    let mut run = |name: &str, f: Lanes| {
        let mut out = [[0.0f32; W]; 4];
        let t = Instant::now();
        for d in 0..iters {
            f(&key, d, &n, &mut out);
            check += out[0][3];
        }
        let s = t.elapsed().as_secs_f64();
        assert!(out == reference, "{name}: lanes differ from the scalar reference");
        print!(", {name} {:.0} M ({:.1}×)", lanes / s / 1e6, scalar / s);
    };
    run("16 lanes baseline (SSE2)", baseline::<M>);
    if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
        // SAFETY: the CPU has AVX2 and FMA (checked just above).
        run("AVX2", |k, d, n, o| unsafe { avx2::<M>(k, d, n, o) });
    }
    if is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512dq") && is_x86_feature_detected!("avx512vl") {
        // SAFETY: the CPU has AVX-512 F, DQ and VL (checked just above).
        run("AVX-512", |k, d, n, o| unsafe { avx512::<M>(k, d, n, o) });
    }
    println!("; every width bit-identical to the scalar reference [{check}]");
}
