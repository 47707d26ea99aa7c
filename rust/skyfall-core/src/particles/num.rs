//! Small numeric helpers of the particle kernels: floors, ceilings and clamps as single
//! instructions on every target (no libm calls, no NaN handling where no NaN reaches).

/// ⌊v⌋ for v ≥ 0 (as an index; no libm call on targets without a rounding instruction).
#[inline]
pub(crate) fn floor_nonneg(v: f32) -> usize {
    // Through i32: one truncating conversion (f32 → u64 has no instruction before AVX-512).
    v as i32 as usize
}

/// A pixel index as f32 (exact below 2²⁴): through u32, one conversion instruction where
/// usize → f32 takes a branchy sequence.
#[inline(always)]
pub(crate) fn idx_f32(v: usize) -> f32 {
    v as u32 as f32
}

/// ⌈v⌉ for v ≥ 0.
#[inline]
pub(crate) fn ceil_nonneg(v: f32) -> usize {
    let t = floor_nonneg(v);
    t + usize::from(idx_f32(t) < v)
}

/// max(x, 0) as one compare-select (`f32::max` also handles NaN, which costs instructions;
/// no NaN reaches here).
#[inline(always)]
pub(crate) fn pos(x: f32) -> f32 {
    if x > 0.0 { x } else { 0.0 }
}

/// x clamped to [0, 1] (see [`pos`]).
#[inline(always)]
pub(crate) fn clamp01(x: f32) -> f32 {
    let x = pos(x);
    if x < 1.0 { x } else { 1.0 }
}

/// min(a, b) as one compare-select.
#[inline(always)]
pub(crate) fn least(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}
