//! The vectorised twins of the 8-bit output stage's per-pixel kernels, chosen at run time.
//!
//! The one module of the workspace allowed `unsafe` (the workspace lint is `deny`; this module
//! alone allows it): raw-pointer loads, the AVX2 gathers, and the calls into
//! `#[target_feature]` functions, each block with its `// SAFETY:` argument. Every kernel here
//! has a scalar twin elsewhere that stays the reference and the fallback, and gives its bits
//! exactly: the same IEEE operations in the same order on each value (no FMA, which would
//! round once where the scalar code rounds twice; FMA only in the encoder's estimate, whose
//! result is an exact code either way), tables read by gathers or register permutes where the
//! scalar code reads them one value at a time. The dispatch never changes the output, only its speed
//! (tests: `frame::srgb8`'s and this module's).
//!
//! Kernels (their scalar twins):
//! - `shade`: a row of 8-bit pixels decoded through the photo's table, hazed, mapped by the
//!   rain's P·C + Q and encoded (`frame::srgb8`'s `shade_row`); the decoding table read by a
//!   gather (AVX2, eight pixels at a time) or from sixteen registers (AVX-512, sixteen; no
//!   gather); the encoder's code by arithmetic (an estimate within 1e-4 of a code, rounded),
//!   its threshold table ([`crate::color::Srgb8Encoder`]) read only where the estimate falls
//!   within 0.001 of a half code.
//! - `transmittance`: a row's haze transmittance ([`Haze::transmittance_row`], exp_neg's
//!   polynomial and the sky's path): the scalar code itself compiled a second time for AVX2 and
//!   FMA (LLVM vectorises it eight wide; it never fuses a multiply and an add on its own, so the
//!   bits are the scalar build's). Safe Rust: only the call is `unsafe`.
//! - `encode`: linear floats to 8-bit sRGB ([`crate::color::encode_srgb8`], the float frame's
//!   encoder), eight at a time as the shading kernel encodes.
//!
//! Levels: AVX-512F, or AVX2 with FMA, on x86_64 (detected with `is_x86_feature_detected!`),
//! else scalar. The environment variable `SKYFALL_SIMD` (`scalar`, `avx2`, `avx512`) caps the
//! level, and `SKYFALL_SCALAR_KERNELS` (a comma-separated list of the kernels' names above, or
//! `all`) forces the named kernels to their scalar twins, for benchmarks and for checking a
//! result on another machine; unknown names are ignored.

#![allow(unsafe_code)]

use crate::haze::{Haze, RowRays};

/// How a kernel runs, in order of width.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Level {
    /// The scalar twin (the reference).
    Scalar,
    /// AVX2 and FMA, eight lanes (x86_64).
    Avx2,
    /// AVX-512 (F), sixteen lanes (x86_64).
    Avx512,
}

impl Level {
    /// The level's name, as `SKYFALL_SIMD` spells it.
    pub fn name(self) -> &'static str {
        match self {
            Level::Scalar => "scalar",
            Level::Avx2 => "avx2",
            Level::Avx512 => "avx512",
        }
    }
}

/// The level each kernel runs at in a frame. Made only from [`best_level`] (lowered by
/// [`Dispatch::capped`] and [`Dispatch::less`]), so a SIMD level is only ever chosen on a CPU
/// that has it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Dispatch {
    shade: Level,
    transmittance: Level,
    encode: Level,
}

/// The kernels' names, as `SKYFALL_SCALAR_KERNELS` lists them.
pub const KERNELS: [&str; 3] = ["shade", "transmittance", "encode"];

impl Dispatch {
    /// Every kernel scalar.
    pub const fn scalar() -> Self {
        Dispatch {
            shade: Level::Scalar,
            transmittance: Level::Scalar,
            encode: Level::Scalar,
        }
    }

    /// The best level this CPU has, for every kernel.
    pub fn best() -> Self {
        let l = best_level();
        Dispatch {
            shade: l,
            transmittance: l,
            encode: l,
        }
    }

    /// [`Self::best`] capped at the level `SKYFALL_SIMD` names (`scalar`, `avx2`, `avx512`),
    /// less the kernels that `SKYFALL_SCALAR_KERNELS` names (read at each call: a frame reads
    /// them once).
    pub fn detect() -> Self {
        let cap = std::env::var("SKYFALL_SIMD").unwrap_or_default();
        let names = std::env::var("SKYFALL_SCALAR_KERNELS").unwrap_or_default();
        let d = Self::best();
        d.capped(Self::parse_level(&cap).unwrap_or(d.shade))
            .less(&names)
    }

    /// A level by its [`Level::name`].
    pub fn parse_level(name: &str) -> Option<Level> {
        [Level::Scalar, Level::Avx2, Level::Avx512]
            .into_iter()
            .find(|l| l.name() == name.trim())
    }

    /// This dispatch with no kernel above `max`.
    pub fn capped(self, max: Level) -> Self {
        Dispatch {
            shade: self.shade.min(max),
            transmittance: self.transmittance.min(max),
            encode: self.encode.min(max),
        }
    }

    /// This dispatch with the kernels `names` lists (comma-separated, or `all`) scalar.
    pub fn less(mut self, names: &str) -> Self {
        for name in names.split(',').map(str::trim) {
            match name {
                "all" => self = Self::scalar(),
                "shade" => self.shade = Level::Scalar,
                "transmittance" => self.transmittance = Level::Scalar,
                "encode" => self.encode = Level::Scalar,
                _ => {}
            }
        }
        self
    }

    /// The shading kernel's level.
    pub fn shade(self) -> Level {
        self.shade
    }

    /// The transmittance kernel's level.
    pub fn transmittance(self) -> Level {
        self.transmittance
    }

    /// The encoder's level.
    pub fn encode(self) -> Level {
        self.encode
    }
}

/// The best level of this CPU.
pub fn best_level() -> Level {
    #[cfg(target_arch = "x86_64")]
    {
        let avx2 = std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma");
        if avx2 && std::arch::is_x86_feature_detected!("avx512f") {
            return Level::Avx512;
        }
        if avx2 {
            return Level::Avx2;
        }
    }
    Level::Scalar
}

/// Every level this CPU has, scalar first (what the tests compare).
pub fn levels() -> Vec<Level> {
    [Level::Scalar, Level::Avx2, Level::Avx512]
        .into_iter()
        .filter(|&l| l <= best_level())
        .collect()
}

/// A row of 8-bit pixels shaded as `frame::srgb8`'s scalar `shade_row::<K>` does (its
/// arguments; `thresholds` the encoder's, [`crate::color::Srgb8Encoder::thresholds`]), as many whole groups of eight
/// pixels as `level` does at once; returns how many pixels it wrote (0 for
/// [`Level::Scalar`]): the caller shades the rest with the scalar code.
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn shade_row<const K: usize>(
    level: Level,
    decode: &[f32; 256],
    thresholds: &[f32; 256],
    air: [f32; 3],
    t: &[f32],
    pq: Option<(&[f32], &[f32], usize)>,
    src: &[u8],
    out: &mut [u8],
) -> usize {
    match level {
        Level::Scalar => 0,
        #[cfg(target_arch = "x86_64")]
        // SAFETY: a `Level::Avx2` comes only from `best_level`, which found AVX2 and FMA on
        // this CPU; the slices are checked inside.
        Level::Avx2 => unsafe { avx2::shade_row::<K>(decode, thresholds, air, t, pq, src, out) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: a `Level::Avx512` comes only from `best_level`, which found AVX-512F (and
        // AVX2 and FMA).
        Level::Avx512 => unsafe {
            avx512::shade_row::<K>(decode, thresholds, air, t, pq, src, out)
        },
        #[cfg(not(target_arch = "x86_64"))]
        _ => 0,
    }
}

/// [`Haze::transmittance_row`] at `level` (the same bits).
#[inline]
pub fn transmittance_row(
    level: Level,
    haze: &Haze,
    rays: &RowRays<'_>,
    depth: &[f32],
    t: &mut [f32],
) {
    match level {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: a `Level::Avx2` comes only from `best_level`, which found AVX2 and FMA.
        Level::Avx2 => unsafe { avx2::transmittance_row(haze, rays, depth, t) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: a `Level::Avx512` comes only from `best_level`, which found AVX-512F (and
        // AVX2 and FMA).
        Level::Avx512 => unsafe { avx512::transmittance_row(haze, rays, depth, t) },
        _ => transmittance_row_scalar(haze, rays, depth, t),
    }
}

/// The scalar twin, not inlined into its caller, so a profile names it.
#[inline(never)]
fn transmittance_row_scalar(haze: &Haze, rays: &RowRays<'_>, depth: &[f32], t: &mut [f32]) {
    haze.transmittance_row(rays, depth, t)
}

/// Linear values to 8-bit sRGB as [`crate::color::Srgb8Encoder::encode`] does, whole groups
/// of eight at `level`; returns how many it wrote (0 for [`Level::Scalar`]).
#[inline]
pub(crate) fn encode_row(
    level: Level,
    thresholds: &[f32; 256],
    x: &[f32],
    out: &mut [u8],
) -> usize {
    match level {
        Level::Scalar => 0,
        #[cfg(target_arch = "x86_64")]
        // SAFETY: a `Level::Avx2` comes only from `best_level`, which found AVX2 and FMA.
        Level::Avx2 => unsafe { avx2::encode_row(thresholds, x, out) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: a `Level::Avx512` comes only from `best_level`, which found AVX-512F (and
        // AVX2 and FMA).
        Level::Avx512 => unsafe { avx512::encode_row(thresholds, x, out) },
        #[cfg(not(target_arch = "x86_64"))]
        _ => 0,
    }
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::{Haze, RowRays};
    use std::arch::x86_64::*;

    /// Eight floats in one unaligned load.
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    fn load8(a: &[f32; 8]) -> __m256 {
        // SAFETY: `a` is eight readable f32s; `loadu` needs no alignment.
        unsafe { _mm256_loadu_ps(a.as_ptr()) }
    }

    /// Eight bytes zero-extended to eight 32-bit lanes.
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    fn bytes8(b: &[u8; 8]) -> __m256i {
        _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(i64::from_le_bytes(*b)))
    }

    /// The encoder: `Srgb8Encoder::encode` of each lane, by arithmetic, a table read only
    /// where the arithmetic cannot tell. `x` is clamped as the scalar code clamps (NaN, −0 and
    /// x ≤ 0 to 0: maxps keeps its second operand, 0, unless the first is greater; above 1 to
    /// 1). Then y ≈ 255·sRGB(x) ([`CODE_PER_OCTAVE`] and [`MANTISSA_POW`]: within 1e-4 of a
    /// code of the formula's value, tested): farther than [`UNSURE`] from a half code, the
    /// formula's code is round(y). Otherwise (0.2 % of values; the whole vector then) it is
    /// ⌊y⌋ or ⌊y⌋ + 1 (that needs an error < 0.5 only), and ⌊y⌋ + 1 exactly when x reaches the
    /// smallest input of that code, `thresholds[⌊y⌋]` (+inf for 255): the scalar encoder's own
    /// final comparison.
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    fn encode8(thresholds: &[f32; 256], x: __m256) -> __m256i {
        let x = _mm256_min_ps(_mm256_max_ps(x, _mm256_setzero_ps()), _mm256_set1_ps(1.0));
        let bits = _mm256_castps_si256(x);
        // x = 2^e · m, m ∈ [1, 2); the curve's part (x > 0.0031308 > 2⁻⁹) has e ∈ [−9, 0]
        let octave = _mm256_min_epi32(
            _mm256_max_epi32(
                _mm256_sub_epi32(_mm256_srli_epi32::<23>(bits), _mm256_set1_epi32(127 - 9)),
                _mm256_setzero_si256(),
            ),
            _mm256_set1_epi32(9),
        );
        let m = _mm256_castsi256_ps(_mm256_or_si256(
            _mm256_and_si256(bits, _mm256_set1_epi32(0x007F_FFFF)),
            _mm256_set1_epi32(0x3F80_0000),
        ));
        let mut pow = _mm256_set1_ps(MANTISSA_POW[0]);
        for c in &MANTISSA_POW[1..] {
            pow = _mm256_fmadd_ps(pow, m, _mm256_set1_ps(*c));
        }
        let k = CODE_PER_OCTAVE;
        let lo = _mm256_setr_ps(k[0], k[1], k[2], k[3], k[4], k[5], k[6], k[7]);
        let hi = _mm256_setr_ps(k[8], k[9], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let scale = _mm256_blendv_ps(
            _mm256_permutevar8x32_ps(lo, octave),
            _mm256_permutevar8x32_ps(hi, octave),
            _mm256_castsi256_ps(_mm256_cmpgt_epi32(octave, _mm256_set1_epi32(7))),
        );
        // 255·(1.055·x^(1/2.4) − 0.055), and 255·12.92·x at and below 0.0031308
        let curve = _mm256_fmsub_ps(scale, pow, _mm256_set1_ps(255.0 * 0.055));
        let linear = _mm256_mul_ps(x, _mm256_set1_ps(255.0 * 12.92));
        let y = _mm256_blendv_ps(
            curve,
            linear,
            _mm256_cmp_ps::<_CMP_LE_OQ>(x, _mm256_set1_ps(0.003_130_8)),
        );
        let clamp = |c: __m256i| {
            _mm256_min_epi32(
                _mm256_max_epi32(c, _mm256_setzero_si256()),
                _mm256_set1_epi32(255),
            )
        };
        // Farther than UNSURE from a half code, y rounds as the formula's value does.
        let near = _mm256_round_ps::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(y);
        let off = _mm256_andnot_ps(_mm256_set1_ps(-0.0), _mm256_sub_ps(y, near));
        let unsure = _mm256_cmp_ps::<_CMP_GT_OQ>(off, _mm256_set1_ps(0.5 - UNSURE));
        if _mm256_movemask_ps(unsure) == 0 {
            return clamp(_mm256_cvtps_epi32(near));
        }
        let floor = clamp(_mm256_cvttps_epi32(y));
        // SAFETY: 0 ≤ floor ≤ 255; `thresholds` has 256 entries; gathers need no alignment.
        let next = unsafe { _mm256_i32gather_ps::<4>(thresholds.as_ptr(), floor) };
        let up = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_GE_OQ>(x, next));
        // up is −1 where x reaches the next code's threshold
        _mm256_sub_epi32(floor, up)
    }

    /// Twenty-four codes (three vectors of eight, each in 0..=255) to their bytes, in order.
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    fn store24(c: [__m256i; 3], out: &mut [u8; 24]) {
        // packus works within 128-bit lanes: bytes [c0 0..3, c1 0..3, c2 0..3, c2 0..3 |
        // c0 4..7, c1 4..7, c2 4..7, c2 4..7] as dwords, put in order by one permute.
        let p01 = _mm256_packus_epi32(c[0], c[1]);
        let p22 = _mm256_packus_epi32(c[2], c[2]);
        let b = _mm256_packus_epi16(p01, p22);
        let r = _mm256_permutevar8x32_epi32(b, _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7));
        let lo = _mm256_castsi256_si128(r);
        let hi = _mm256_extracti128_si256::<1>(r);
        let words = [
            _mm_cvtsi128_si64(lo),
            _mm_extract_epi64::<1>(lo),
            _mm_cvtsi128_si64(hi),
        ];
        for (o, w) in out.as_chunks_mut::<8>().0.iter_mut().zip(words) {
            *o = w.to_le_bytes();
        }
    }

    /// Per group of eight values of eight RGB pixels (values 8m..8m + 7), each value's pixel.
    const PIXEL: [[i32; 8]; 3] = [
        [0, 0, 0, 1, 1, 1, 2, 2],
        [2, 3, 3, 3, 4, 4, 4, 5],
        [5, 5, 6, 6, 6, 7, 7, 7],
    ];
    /// And its channel.
    const CHANNEL: [[i32; 8]; 3] = [
        [0, 1, 2, 0, 1, 2, 0, 1],
        [2, 0, 1, 2, 0, 1, 2, 0],
        [1, 2, 0, 1, 2, 0, 1, 2],
    ];

    /// 255 · 1.055 · 2^(5e/12) for the octaves e = −9..=0 (x^(1/2.4) = 2^(e/2.4) · m^(1/2.4)):
    /// the curve's codes per unit of m^(1/2.4) (tested against the formula).
    pub(super) const CODE_PER_OCTAVE: [f32; 10] = [
        19.995_403, 26.690_66, 35.627_758, 47.557_35, 63.481_445, 84.737_564, 113.111_08,
        150.985_18, 201.541_03, 269.025,
    ];
    /// m^(1/2.4) on [1, 2) as a polynomial of degree 6 in m, highest power first (least
    /// squares on Chebyshev nodes; relative error 2.2e-7 with these f32 coefficients, 6e-5 of
    /// a code at most; tested).
    pub(super) const MANTISSA_POW: [f32; 7] = [
        -0.002_744_525_2,
        0.029_938_081,
        -0.141_533_43,
        0.383_272_68,
        -0.679_980_34,
        1.059_697_7,
        0.351_35,
    ];
    /// How near a half code (in codes) the estimate may fall before the threshold settles it:
    /// well above its error (6e-5, and its f32 rounding, < 1e-4) and the formula's own f32
    /// rounding (< 1e-4), so farther away round(estimate) is the formula's code.
    pub(super) const UNSURE: f32 = 0.001;

    #[target_feature(enable = "avx2,fma")]
    #[inline]
    fn idx(a: [i32; 8]) -> __m256i {
        _mm256_setr_epi32(a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7])
    }

    /// See [`super::shade_row`]: whole groups of eight pixels; returns the pixels written.
    #[allow(clippy::too_many_arguments)]
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn shade_row<const K: usize>(
        decode: &[f32; 256],
        thresholds: &[f32; 256],
        air: [f32; 3],
        t: &[f32],
        pq: Option<(&[f32], &[f32], usize)>,
        src: &[u8],
        out: &mut [u8],
    ) -> usize {
        let mut n = t.len().min(src.len() / 3).min(out.len() / 3);
        // The maps' planes, each cut to the pixels (the caller's q holds K planes `stride`
        // apart; a plane it lacks ends the row there, so no value is read out of bounds).
        let planes: Option<(&[f32], [&[f32]; K])> = pq.map(|(p, q, stride)| {
            n = n.min(p.len());
            let plane = |c: usize| q.get(c * stride..).unwrap_or_default();
            let qs: [&[f32]; K] = std::array::from_fn(plane);
            for q in &qs {
                n = n.min(q.len());
            }
            (p, qs)
        });
        let n8 = n / 8 * 8;
        let pix = PIXEL.map(|a| idx(a));
        let chan = CHANNEL.map(|a| idx(a));
        let air3 = _mm256_setr_ps(air[0], air[1], air[2], 0.0, 0.0, 0.0, 0.0, 0.0);
        let air8 = chan.map(|c| _mm256_permutevar8x32_ps(air3, c));
        let one = _mm256_set1_ps(1.0);
        let is =
            |c: __m256i, k: i32| _mm256_castsi256_ps(_mm256_cmpeq_epi32(c, _mm256_set1_epi32(k)));
        let green = chan.map(|c| is(c, 1));
        let blue = chan.map(|c| is(c, 2));
        let (src24, _) = src[..3 * n8].as_chunks::<24>();
        let (out24, _) = out[..3 * n8].as_chunks_mut::<24>();
        let (t8, _) = t[..n8].as_chunks::<8>();
        for (g, ((s, o), tc)) in src24.iter().zip(out24).zip(t8).enumerate() {
            let (bytes, _) = s.as_chunks::<8>();
            let tv = load8(tc);
            let maps = match &planes {
                None => None,
                Some((p, qs)) => {
                    let mut qv = [_mm256_setzero_ps(); K];
                    for (v, q) in qv.iter_mut().zip(qs) {
                        *v = load8(&q.as_chunks::<8>().0[g]);
                    }
                    Some((load8(&p.as_chunks::<8>().0[g]), qv))
                }
            };
            let mut codes = [_mm256_setzero_si256(); 3];
            for m in 0..3 {
                // SAFETY: the lanes are bytes, 0..=255; `decode` has 256 entries.
                let v = unsafe { _mm256_i32gather_ps::<4>(decode.as_ptr(), bytes8(&bytes[m])) };
                let tm = _mm256_permutevar8x32_ps(tv, pix[m]);
                // v·t + air·(1 − t), rounded as the scalar code rounds it
                let mut h = _mm256_add_ps(
                    _mm256_mul_ps(v, tm),
                    _mm256_mul_ps(air8[m], _mm256_sub_ps(one, tm)),
                );
                if let Some((p, qs)) = &maps {
                    let pm = _mm256_permutevar8x32_ps(*p, pix[m]);
                    let qm = if K == 1 {
                        _mm256_permutevar8x32_ps(qs[0], pix[m])
                    } else {
                        let r = _mm256_permutevar8x32_ps(qs[0], pix[m]);
                        let gq = _mm256_permutevar8x32_ps(qs[1 % K], pix[m]);
                        let bq = _mm256_permutevar8x32_ps(qs[2 % K], pix[m]);
                        _mm256_blendv_ps(_mm256_blendv_ps(r, gq, green[m]), bq, blue[m])
                    };
                    h = _mm256_add_ps(_mm256_mul_ps(h, pm), qm);
                }
                codes[m] = encode8(thresholds, h);
            }
            store24(codes, o);
        }
        n8
    }

    /// See [`super::encode_row`].
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn encode_row(thresholds: &[f32; 256], x: &[f32], out: &mut [u8]) -> usize {
        let n24 = x.len().min(out.len()) / 24 * 24;
        let (x24, _) = x[..n24].as_chunks::<24>();
        let (o24, _) = out[..n24].as_chunks_mut::<24>();
        for (x, o) in x24.iter().zip(o24) {
            let (v, _) = x.as_chunks::<8>();
            let codes = [0, 1, 2].map(|m| encode8(thresholds, load8(&v[m])));
            store24(codes, o);
        }
        n24
    }

    /// [`Haze::transmittance_row`] compiled for AVX2 and FMA.
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn transmittance_row(haze: &Haze, rays: &RowRays<'_>, depth: &[f32], t: &mut [f32]) {
        haze.transmittance_row(rays, depth, t)
    }
}

#[cfg(target_arch = "x86_64")]
mod avx512 {
    use super::avx2::{CODE_PER_OCTAVE, MANTISSA_POW, UNSURE};
    use super::{Haze, RowRays};
    use std::arch::x86_64::*;

    /// Sixteen floats in one unaligned load.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn load16(a: &[f32; 16]) -> __m512 {
        // SAFETY: `a` is sixteen readable f32s; `loadu` needs no alignment.
        unsafe { _mm512_loadu_ps(a.as_ptr()) }
    }

    /// A 256-entry table in sixteen registers.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn table(t: &[f32; 256]) -> [__m512; 16] {
        let (rows, _) = t.as_chunks::<16>();
        let mut r = [_mm512_setzero_ps(); 16];
        for (v, row) in r.iter_mut().zip(rows) {
            *v = load16(row);
        }
        r
    }

    /// `t[k]` for each lane's k ∈ 0..=255, from registers: eight two-register permutes (by
    /// k's low five bits), then a three-level blend by bits 5, 6 and 7. No gather.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn lookup(t: &[__m512; 16], k: __m512i) -> __m512 {
        let mut r = [_mm512_setzero_ps(); 8];
        for (j, v) in r.iter_mut().enumerate() {
            *v = _mm512_permutex2var_ps(t[2 * j], k, t[2 * j + 1]);
        }
        let bit = |b: i32| _mm512_test_epi32_mask(k, _mm512_set1_epi32(b));
        let (b5, b6, b7) = (bit(32), bit(64), bit(128));
        let s = [0, 1, 2, 3].map(|j| _mm512_mask_blend_ps(b5, r[2 * j], r[2 * j + 1]));
        let u0 = _mm512_mask_blend_ps(b6, s[0], s[1]);
        let u1 = _mm512_mask_blend_ps(b6, s[2], s[3]);
        _mm512_mask_blend_ps(b7, u0, u1)
    }

    /// The encoder of `super::avx2::encode8`, sixteen lanes, its thresholds (where needed)
    /// read by [`lookup`].
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn encode16(thresholds: &[__m512; 16], x: __m512) -> __m512i {
        let x = _mm512_min_ps(_mm512_max_ps(x, _mm512_setzero_ps()), _mm512_set1_ps(1.0));
        let bits = _mm512_castps_si512(x);
        let octave = _mm512_min_epi32(
            _mm512_max_epi32(
                _mm512_sub_epi32(_mm512_srli_epi32::<23>(bits), _mm512_set1_epi32(127 - 9)),
                _mm512_setzero_si512(),
            ),
            _mm512_set1_epi32(9),
        );
        let m = _mm512_castsi512_ps(_mm512_or_si512(
            _mm512_and_si512(bits, _mm512_set1_epi32(0x007F_FFFF)),
            _mm512_set1_epi32(0x3F80_0000),
        ));
        let mut pow = _mm512_set1_ps(MANTISSA_POW[0]);
        for c in &MANTISSA_POW[1..] {
            pow = _mm512_fmadd_ps(pow, m, _mm512_set1_ps(*c));
        }
        let k = CODE_PER_OCTAVE;
        let per_octave = _mm512_setr_ps(
            k[0], k[1], k[2], k[3], k[4], k[5], k[6], k[7], k[8], k[9], 0.0, 0.0, 0.0, 0.0, 0.0,
            0.0,
        );
        let curve = _mm512_fmsub_ps(
            _mm512_permutexvar_ps(octave, per_octave),
            pow,
            _mm512_set1_ps(255.0 * 0.055),
        );
        let linear = _mm512_mul_ps(x, _mm512_set1_ps(255.0 * 12.92));
        let low = _mm512_cmp_ps_mask::<_CMP_LE_OQ>(x, _mm512_set1_ps(0.003_130_8));
        let y = _mm512_mask_blend_ps(low, curve, linear);
        let clamp = |c: __m512i| {
            _mm512_min_epi32(
                _mm512_max_epi32(c, _mm512_setzero_si512()),
                _mm512_set1_epi32(255),
            )
        };
        // Farther than UNSURE from a half code, y rounds as the formula's value does.
        let near = _mm512_roundscale_ps::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(y);
        let off = _mm512_abs_ps(_mm512_sub_ps(y, near));
        if _mm512_cmp_ps_mask::<_CMP_GT_OQ>(off, _mm512_set1_ps(0.5 - UNSURE)) == 0 {
            return clamp(_mm512_cvtps_epi32(near));
        }
        let floor = clamp(_mm512_cvttps_epi32(y));
        let up = _mm512_cmp_ps_mask::<_CMP_GE_OQ>(x, lookup(thresholds, floor));
        _mm512_mask_add_epi32(floor, up, floor, _mm512_set1_epi32(1))
    }

    /// Sixteen bytes zero-extended to sixteen 32-bit lanes.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn bytes16(b: &[u8; 16]) -> __m512i {
        let v = u128::from_le_bytes(*b);
        _mm512_cvtepu8_epi32(_mm_set_epi64x((v >> 64) as i64, v as i64))
    }

    /// Sixteen codes (0..=255) to their bytes.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn store16(c: __m512i, out: &mut [u8; 16]) {
        let b = _mm512_cvtepi32_epi8(c);
        let (lo, hi) = (
            _mm_cvtsi128_si64(b) as u64,
            _mm_extract_epi64::<1>(b) as u64,
        );
        *out = (u128::from(lo) | (u128::from(hi) << 64)).to_le_bytes();
    }

    /// Per group of sixteen values of sixteen RGB pixels, each value's pixel (`PIXEL[m][j]` =
    /// (16m + j) / 3) and channel.
    const PIXEL: [[i32; 16]; 3] = {
        let mut p = [[0; 16]; 3];
        let mut i = 0;
        while i < 48 {
            p[i / 16][i % 16] = (i / 3) as i32;
            i += 1;
        }
        p
    };
    const CHANNEL: [[i32; 16]; 3] = {
        let mut p = [[0; 16]; 3];
        let mut i = 0;
        while i < 48 {
            p[i / 16][i % 16] = (i % 3) as i32;
            i += 1;
        }
        p
    };

    #[target_feature(enable = "avx512f")]
    #[inline]
    fn idx(a: &[i32; 16]) -> __m512i {
        // SAFETY: `a` is sixteen readable i32s; `loadu` needs no alignment.
        unsafe { _mm512_loadu_si512(a.as_ptr().cast()) }
    }

    /// A lane mask from sixteen flags.
    fn mask(f: impl Fn(usize) -> bool) -> __mmask16 {
        (0..16).filter(|&j| f(j)).fold(0, |m, j| m | (1 << j))
    }

    /// See [`super::shade_row`]: whole groups of sixteen pixels; returns the pixels written.
    #[allow(clippy::too_many_arguments)]
    #[target_feature(enable = "avx512f")]
    pub(super) fn shade_row<const K: usize>(
        decode: &[f32; 256],
        thresholds: &[f32; 256],
        air: [f32; 3],
        t: &[f32],
        pq: Option<(&[f32], &[f32], usize)>,
        src: &[u8],
        out: &mut [u8],
    ) -> usize {
        let mut n = t.len().min(src.len() / 3).min(out.len() / 3);
        let planes: Option<(&[f32], [&[f32]; K])> = pq.map(|(p, q, stride)| {
            n = n.min(p.len());
            let plane = |c: usize| q.get(c * stride..).unwrap_or_default();
            let qs: [&[f32]; K] = std::array::from_fn(plane);
            for q in &qs {
                n = n.min(q.len());
            }
            (p, qs)
        });
        let n16 = n / 16 * 16;
        let (dec, thr) = (table(decode), table(thresholds));
        let pix = [idx(&PIXEL[0]), idx(&PIXEL[1]), idx(&PIXEL[2])];
        let chan = [idx(&CHANNEL[0]), idx(&CHANNEL[1]), idx(&CHANNEL[2])];
        let air3 = _mm512_setr_ps(
            air[0], air[1], air[2], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
        );
        let air16 = [
            _mm512_permutexvar_ps(chan[0], air3),
            _mm512_permutexvar_ps(chan[1], air3),
            _mm512_permutexvar_ps(chan[2], air3),
        ];
        let green = [0, 1, 2].map(|m| mask(|j| CHANNEL[m][j] == 1));
        let blue = [0, 1, 2].map(|m| mask(|j| CHANNEL[m][j] == 2));
        let one = _mm512_set1_ps(1.0);
        let (src48, _) = src[..3 * n16].as_chunks::<48>();
        let (out48, _) = out[..3 * n16].as_chunks_mut::<48>();
        let (t16, _) = t[..n16].as_chunks::<16>();
        for (g, ((s, o), tc)) in src48.iter().zip(out48).zip(t16).enumerate() {
            let (bytes, _) = s.as_chunks::<16>();
            let (outs, _) = o.as_chunks_mut::<16>();
            let tv = load16(tc);
            let maps = match &planes {
                None => None,
                Some((p, qs)) => {
                    let mut qv = [_mm512_setzero_ps(); K];
                    for (v, q) in qv.iter_mut().zip(qs) {
                        *v = load16(&q.as_chunks::<16>().0[g]);
                    }
                    Some((load16(&p.as_chunks::<16>().0[g]), qv))
                }
            };
            for m in 0..3 {
                let v = lookup(&dec, bytes16(&bytes[m]));
                let tm = _mm512_permutexvar_ps(pix[m], tv);
                // v·t + air·(1 − t), rounded as the scalar code rounds it
                let mut h = _mm512_add_ps(
                    _mm512_mul_ps(v, tm),
                    _mm512_mul_ps(air16[m], _mm512_sub_ps(one, tm)),
                );
                if let Some((p, qs)) = &maps {
                    let pm = _mm512_permutexvar_ps(pix[m], *p);
                    let qm = if K == 1 {
                        _mm512_permutexvar_ps(pix[m], qs[0])
                    } else {
                        let r = _mm512_permutexvar_ps(pix[m], qs[0]);
                        let gq = _mm512_permutexvar_ps(pix[m], qs[1 % K]);
                        let bq = _mm512_permutexvar_ps(pix[m], qs[2 % K]);
                        _mm512_mask_blend_ps(blue[m], _mm512_mask_blend_ps(green[m], r, gq), bq)
                    };
                    h = _mm512_add_ps(_mm512_mul_ps(h, pm), qm);
                }
                store16(encode16(&thr, h), &mut outs[m]);
            }
        }
        n16
    }

    /// See [`super::encode_row`].
    #[target_feature(enable = "avx512f")]
    pub(super) fn encode_row(thresholds: &[f32; 256], x: &[f32], out: &mut [u8]) -> usize {
        let n16 = x.len().min(out.len()) / 16 * 16;
        let thr = table(thresholds);
        let (x16, _) = x[..n16].as_chunks::<16>();
        let (o16, _) = out[..n16].as_chunks_mut::<16>();
        for (x, o) in x16.iter().zip(o16) {
            store16(encode16(&thr, load16(x)), o);
        }
        n16
    }

    /// [`Haze::transmittance_row`] compiled for AVX-512F.
    #[target_feature(enable = "avx512f")]
    pub(super) fn transmittance_row(haze: &Haze, rays: &RowRays<'_>, depth: &[f32], t: &mut [f32]) {
        haze.transmittance_row(rays, depth, t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::{Srgb8Encoder, encode_srgb8_at, encode_srgb8_formula};
    use crate::haze::ViewRays;
    use crate::scene::camera::Camera;
    use glam::{Mat3, Quat, Vec3};

    /// The SIMD levels under test: every one the CPU has, AVX2 at least wherever it has AVX2
    /// and FMA (asserted, so the comparisons below are not the scalar code against itself on
    /// such a CPU).
    fn simd_levels() -> Vec<Level> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            assert!(best_level() >= Level::Avx2);
        }
        levels()
            .into_iter()
            .filter(|&l| l != Level::Scalar)
            .collect()
    }

    #[test]
    fn the_scalar_kernels_list_is_read() {
        let best = Dispatch::best();
        assert_eq!(best.less("all"), Dispatch::scalar());
        assert_eq!(best.less(""), best);
        assert_eq!(best.less("nonsense"), best);
        let d = best.less("shade, encode");
        assert_eq!(
            (d.shade(), d.transmittance(), d.encode()),
            (Level::Scalar, best.transmittance(), Level::Scalar)
        );
        assert_eq!(best.less("transmittance").transmittance(), Level::Scalar);
        assert!(
            KERNELS
                .iter()
                .all(|k| best.less(k) != best || best == Dispatch::scalar())
        );
    }

    #[test]
    fn the_encoders_estimate_is_within_a_ten_thousandth_of_a_code() {
        // The constants are what they say, and the estimate's error (evaluated here in f64; the
        // kernel's f32 rounding adds < 1e-4 of a code) is a tenth of the margin it rounds with.
        #[cfg(target_arch = "x86_64")]
        {
            use avx2::{CODE_PER_OCTAVE, MANTISSA_POW, UNSURE};
            for (i, &k) in CODE_PER_OCTAVE.iter().enumerate() {
                let want = 255.0 * 1.055 * 2f64.powf(5.0 * (i as f64 - 9.0) / 12.0);
                assert!((f64::from(k) / want - 1.0).abs() < 1e-7, "{i}");
            }
            let mut worst = 0.0f64;
            for i in 0..=1_000_000 {
                let x = 0.003_130_8 + (1.0 - 0.003_130_8) * f64::from(i) / 1e6;
                let e = x.log2().floor().max(-9.0);
                let m = x / 2f64.powf(e);
                let pow = MANTISSA_POW.iter().fold(0.0, |p, &c| p * m + f64::from(c));
                let est = f64::from(CODE_PER_OCTAVE[(e + 9.0) as usize]) * pow - 255.0 * 0.055;
                let exact = 255.0 * (1.055 * x.powf(1.0 / 2.4) - 0.055);
                worst = worst.max((est - exact).abs());
            }
            assert!(worst < 1e-4 && worst < f64::from(UNSURE) / 10.0, "{worst}");
        }
    }

    #[test]
    fn the_simd_encoder_gives_the_formula_bits() {
        // The specials, every threshold and its neighbours, a sweep of bit patterns over
        // [0, 1]; the short head (specials and thresholds) through every lane remainder and
        // unaligned starts, the whole list from a few starts.
        let thresholds = Srgb8Encoder::new().thresholds();
        let mut xs: Vec<f32> = vec![
            -1.0,
            -0.0,
            0.0,
            f32::MIN_POSITIVE,
            1e-40,
            0.999_999_9,
            1.0,
            1.000_000_1,
            1.5,
            f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
            0.003_130_8,
            0.003_130_9,
        ];
        xs.extend(thresholds.iter().flat_map(|&v| {
            let b = v.to_bits();
            [f32::from_bits(b - 1), v, f32::from_bits(b + 1)]
        }));
        let head = xs.len();
        xs.extend((0..400_000u32).map(|i| f32::from_bits(i * (1.0f32.to_bits() / 400_000))));
        let want: Vec<u8> = xs.iter().map(|&x| encode_srgb8_formula(x)).collect();
        let check = |level: Level, start: usize, n: usize| {
            let x = &xs[start..start + n];
            let mut out = vec![0u8; n];
            let done = encode_row(level, thresholds, x, &mut out);
            assert!(n - done < 24, "{level:?} did {done} of {n}");
            assert_eq!(
                out[..done],
                want[start..start + done],
                "{level:?} start {start}"
            );
            let mut all = vec![0u8; n];
            encode_srgb8_at(level, x, &mut all);
            assert_eq!(all, want[start..start + n], "{level:?} start {start} n {n}");
        };
        for level in simd_levels() {
            for start in 0..9 {
                for rem in 0..25 {
                    check(level, start, head - 48 + rem);
                }
            }
            for start in [0, 5] {
                check(level, start, xs.len() - start);
            }
        }
    }

    #[test]
    fn the_simd_encoder_gives_the_scalar_bits_on_every_float_in_0_1() {
        // Every float bit pattern from 0 to 1 in an optimised build (`cargo test --release`:
        // 1 065 353 217 values), every 61st in a debug build, each level against the scalar
        // encoder (the formula's bits, tested in color/).
        let stride: u32 = if cfg!(debug_assertions) { 61 } else { 1 };
        let enc = Srgb8Encoder::new();
        let thresholds = enc.thresholds();
        let one = 1.0f32.to_bits();
        let mut checked = 0u64;
        for level in simd_levels() {
            let mut x = Vec::with_capacity(1 << 20);
            let (mut got, mut want) = (vec![0u8; 1 << 20], vec![0u8; 1 << 20]);
            let mut next = 0u32;
            while next <= one {
                x.clear();
                while x.len() < 1 << 20 && next <= one {
                    x.push(f32::from_bits(next));
                    next += stride;
                }
                let n = x.len();
                let done = encode_row(level, thresholds, &x, &mut got[..n]);
                for (w, &v) in want[..done].iter_mut().zip(&x) {
                    *w = enc.encode(v);
                }
                assert!(n - done < 24);
                if let Some(i) = (0..done).find(|&i| got[i] != want[i]) {
                    assert_eq!(got[i], want[i], "{level:?}: {:e}", x[i]);
                }
                checked += done as u64;
            }
        }
        assert!(checked > 1_000_000 || simd_levels().is_empty());
    }

    #[test]
    fn the_simd_transmittance_gives_the_scalar_bits() {
        // A camera pitched up (sky pixels on the rows above the horizon), rows of depths with
        // sky among them, clear and hazy, a finite and an infinite ceiling, every remainder of
        // eight and of sixteen, unaligned starts.
        let rot = Mat3::from_quat(Quat::from_rotation_x(0.3));
        let cam = Camera::new(97, 40, [50.0, 50.0, 48.5, 20.0], Vec3::ZERO, rot).unwrap();
        let rays = ViewRays::new(&cam);
        let depth: Vec<f32> = (0..97)
            .map(|x| match x % 11 {
                0 | 4 => f32::INFINITY,
                3 => 0.0,
                k => 0.5 * k as f32 + x as f32 * 13.7,
            })
            .collect();
        let mut checked = 0;
        for (sigma, ceiling) in [
            (0.0, 600.0),
            (0.003, 600.0),
            (0.05, f32::INFINITY),
            (2.0, 30.0),
        ] {
            let haze = Haze::new(sigma, [0.4; 3], ceiling).unwrap();
            for (level, y) in simd_levels()
                .into_iter()
                .flat_map(|l| [(l, 0u32), (l, 7), (l, 39)])
            {
                for start in 0..5 {
                    for n in 0..=33 {
                        let cols = start..start + n;
                        let r = rays.row(y, cols.clone());
                        let (mut a, mut b) = (vec![-1.0f32; n], vec![-2.0f32; n]);
                        transmittance_row(level, &haze, &r, &depth[cols.clone()], &mut a);
                        haze.transmittance_row(&r, &depth[cols], &mut b);
                        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                        assert_eq!(bits(&a), bits(&b), "sigma {sigma} y {y} {start} {n}");
                        checked += n;
                    }
                }
                // a whole row too
                let r = rays.row(y, 0..97);
                let (mut a, mut b) = (vec![0.0f32; 97], vec![0.0f32; 97]);
                transmittance_row(level, &haze, &r, &depth, &mut a);
                haze.transmittance_row(&r, &depth, &mut b);
                assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
                assert!(sigma == 0.0 || a.iter().any(|&t| t > 0.0 && t < 1.0));
            }
        }
        assert!(checked > 1000);
    }
}
