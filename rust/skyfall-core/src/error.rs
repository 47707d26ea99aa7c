//! Errors of the core crate: every message names the parameter, its value and the valid range.

use std::fmt;

/// A parameter's value as the user wrote it: an integer parameter's whole value without
/// `.0` (`20000`), any other as Python writes a float (`180.0`, `1e-300`, `NaN`).
struct Shown(f64, bool);

impl fmt::Display for Shown {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Shown(v, integer) = *self;
        if integer && v.is_finite() && v.fract() == 0.0 && v.abs() < 1e300 {
            write!(f, "{v:.0}")
        } else {
            write!(f, "{v:?}")
        }
    }
}

/// Result with the core crate's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

/// Where a bad value sits: a scalar parameter or one element of an array parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    /// Parameter name as the user wrote it (`diameter_mm`).
    pub name: &'static str,
    /// Element index for array inputs.
    pub index: Option<usize>,
}

impl fmt::Display for Param {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.index {
            Some(i) => write!(f, "{}[{}]", self.name, i),
            None => write!(f, "{}", self.name),
        }
    }
}

/// Everything that can go wrong in the core crate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// A number outside its valid range (NaN and infinities included).
    /// (The value prints as Python writes a float: `180.0`, `1e-300`, but `NaN`; an integer
    /// parameter's whole value as an integer: `width = 20000`.)
    #[error("{param} = {} is outside the valid range {range}", Shown(*.value, *.integer))]
    OutOfRange {
        /// The offending parameter.
        param: Param,
        /// Its value.
        value: f64,
        /// The valid range, with units, e.g. `[0, 8] mm`.
        range: String,
        /// Whether the parameter is an integer (a count, pixels, a seed): its whole values
        /// print without `.0`.
        integer: bool,
    },
    /// A value that is not allowed for another reason (an unknown model name, unsorted input).
    #[error("{param}: {message}")]
    Invalid {
        /// The offending parameter.
        param: Param,
        /// What is wrong and what is accepted.
        message: String,
    },
    /// A value within its range that this request cannot use, with what would work.
    #[error("{param} = {value:?} {message}")]
    Unusable {
        /// The offending parameter.
        param: Param,
        /// Its value.
        value: f64,
        /// Why, and what would work.
        message: String,
    },
    /// A request whose result would exceed the memory budget; refused before allocating.
    #[error(
        "{what} would need {bytes} bytes ({gib:.2} GiB), over the budget of {budget} bytes ({budget_gib:.2} GiB); ask for fewer or smaller items"
    )]
    TooLarge {
        /// What was requested.
        what: String,
        /// Bytes it would need.
        bytes: u128,
        /// The same in GiB.
        gib: f64,
        /// The budget in bytes.
        budget: u64,
        /// The budget in GiB.
        budget_gib: f64,
    },
    /// Array arguments whose lengths do not broadcast.
    #[error("{param} has length {len}, expected 1 or {expected}")]
    Length {
        /// The offending parameter.
        param: Param,
        /// Its length.
        len: usize,
        /// The length of the broadcast result.
        expected: usize,
    },
    /// An allocation the system refused (an address-space limit, an exhausted machine).
    #[error("out of memory: {what} needs {bytes} bytes ({mib:.1} MiB) that could not be allocated")]
    OutOfMemory {
        /// What was being allocated.
        what: String,
        /// Bytes asked for.
        bytes: u128,
        /// The same in MiB.
        mib: f64,
    },
    /// A long computation stopped because its caller asked it to (Ctrl-C in Python).
    #[error("{what} was cancelled")]
    Cancelled {
        /// What was stopped.
        what: &'static str,
    },
}

impl Error {
    /// Builds a [`Error::TooLarge`].
    pub fn too_large(what: String, bytes: u128, budget: u64) -> Self {
        const GIB: f64 = (1u64 << 30) as f64;
        Error::TooLarge {
            what,
            bytes,
            gib: bytes as f64 / GIB,
            budget,
            budget_gib: budget as f64 / GIB,
        }
    }

    /// Builds an [`Error::OutOfMemory`] for `len` values of `T`.
    pub fn out_of_memory<T>(what: impl Into<String>, len: usize) -> Self {
        const MIB: f64 = (1u64 << 20) as f64;
        let bytes = len as u128 * std::mem::size_of::<T>() as u128;
        Error::OutOfMemory {
            what: what.into(),
            bytes,
            mib: bytes as f64 / MIB,
        }
    }
}

/// A vector of `len` copies of `value`, or [`Error::OutOfMemory`] where `vec![value; len]`
/// would abort the process.
pub fn try_filled<T: Clone>(what: &str, len: usize, value: T) -> Result<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(len)
        .map_err(|_| Error::out_of_memory::<T>(what, len))?;
    v.resize(len, value);
    Ok(v)
}

/// [`try_filled`] for large buffers: reserved fallibly, then filled by the thread pool, so the
/// pages are first touched in parallel (as the kernels that write them next would).
pub fn try_filled_par<T: Clone + Send + Sync>(what: &str, len: usize, value: T) -> Result<Vec<T>> {
    use rayon::prelude::*;
    let mut v = Vec::new();
    v.try_reserve_exact(len)
        .map_err(|_| Error::out_of_memory::<T>(what, len))?;
    v.par_extend(rayon::iter::repeat_n(value, len));
    Ok(v)
}

/// `items` through `f` in parallel (at least `min_len` items per task), the `Some`s kept in
/// their order, in a vector grown fallibly: [`Error::OutOfMemory`] naming `what` where
/// `collect` would abort the process. Works through chunks of 2^16 items, so besides the
/// result it holds one chunk's `Option`s.
pub fn try_par_filter_map<T: Sync, U: Send>(
    what: &str,
    items: &[T],
    min_len: usize,
    f: impl Fn(&T) -> Option<U> + Sync + Send,
) -> Result<Vec<U>> {
    use rayon::prelude::*;
    const CHUNK: usize = 1 << 16;
    let first = items.len().min(CHUNK);
    let mut part: Vec<Option<U>> = Vec::new();
    part.try_reserve_exact(first)
        .map_err(|_| Error::out_of_memory::<Option<U>>(what, first))?;
    let mut out: Vec<U> = Vec::new();
    for chunk in items.chunks(CHUNK) {
        chunk
            .par_iter()
            .with_min_len(min_len.max(1))
            .map(&f)
            .collect_into_vec(&mut part);
        let n = part.iter().filter(|s| s.is_some()).count();
        out.try_reserve(n)
            .map_err(|_| Error::out_of_memory::<U>(what, out.len() + n))?;
        out.extend(part.drain(..).flatten());
    }
    Ok(out)
}

/// The parts one after the other, in a vector reserved fallibly (as `concat` would abort).
pub fn try_concat<T>(what: &str, parts: Vec<Vec<T>>) -> Result<Vec<T>> {
    let n: usize = parts.iter().map(Vec::len).sum();
    let mut out = Vec::new();
    out.try_reserve_exact(n)
        .map_err(|_| Error::out_of_memory::<T>(what, n))?;
    for p in parts {
        out.extend(p);
    }
    Ok(out)
}

/// A vector with room for `n` values reserved fallibly.
pub fn try_with_capacity<T>(what: &str, n: usize) -> Result<Vec<T>> {
    let mut out = Vec::new();
    out.try_reserve_exact(n)
        .map_err(|_| Error::out_of_memory::<T>(what, n))?;
    Ok(out)
}

/// [`Error::Cancelled`] once `cancel` is set: the check long loops make between chunks.
#[inline]
pub fn check_cancel(cancel: &std::sync::atomic::AtomicBool, what: &'static str) -> Result<()> {
    if cancel.load(std::sync::atomic::Ordering::Relaxed) {
        Err(Error::Cancelled { what })
    } else {
        Ok(())
    }
}

/// An interval with units, used to validate inputs: closed unless an end is marked open.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    /// Lower bound (inclusive unless `lo_open`).
    pub lo: f64,
    /// Upper bound (inclusive unless `hi_open`).
    pub hi: f64,
    /// Whether the lower bound is excluded.
    pub lo_open: bool,
    /// Whether the upper bound is excluded.
    pub hi_open: bool,
    /// Unit shown in messages.
    pub unit: &'static str,
    /// Whether the values are integers (a count, pixels, a seed): messages print them so.
    pub integer: bool,
}

impl Range {
    /// `[lo, hi] unit`.
    pub const fn closed(lo: f64, hi: f64, unit: &'static str) -> Self {
        Range {
            lo,
            hi,
            lo_open: false,
            hi_open: false,
            unit,
            integer: false,
        }
    }
    /// The same range over integers (messages print whole values without `.0`).
    pub const fn integers(self) -> Self {
        Range {
            integer: true,
            ..self
        }
    }
    /// `(lo, hi] unit`.
    pub const fn open_closed(lo: f64, hi: f64, unit: &'static str) -> Self {
        Range {
            lo_open: true,
            ..Range::closed(lo, hi, unit)
        }
    }
    /// `[lo, hi) unit`.
    pub const fn closed_open(lo: f64, hi: f64, unit: &'static str) -> Self {
        Range {
            hi_open: true,
            ..Range::closed(lo, hi, unit)
        }
    }
    /// `(lo, hi) unit`; `(-inf, inf)` accepts every finite number.
    pub const fn open(lo: f64, hi: f64, unit: &'static str) -> Self {
        Range {
            lo_open: true,
            hi_open: true,
            ..Range::closed(lo, hi, unit)
        }
    }

    /// Whether `value` lies in the range (NaN never does).
    #[inline]
    pub fn contains(&self, value: f64) -> bool {
        let lo_ok = if self.lo_open {
            value > self.lo
        } else {
            value >= self.lo
        };
        let hi_ok = if self.hi_open {
            value < self.hi
        } else {
            value <= self.hi
        };
        lo_ok && hi_ok
    }

    /// Checks one value (NaN fails every comparison and so is rejected).
    pub fn check(&self, name: &'static str, index: Option<usize>, value: f64) -> Result<f64> {
        if self.contains(value) {
            Ok(value)
        } else {
            Err(Error::OutOfRange {
                param: Param { name, index },
                value,
                range: self.to_string(),
                integer: self.integer,
            })
        }
    }

    /// Checks every element of a slice; indices are reported only for slices longer than one.
    pub fn check_all(&self, name: &'static str, values: &[f64]) -> Result<()> {
        // The common case in one plain pass (no error built per element); the first value
        // outside is looked for only when there is one.
        if values.iter().all(|&v| self.contains(v)) {
            return Ok(());
        }
        let many = values.len() > 1;
        for (i, &v) in values.iter().enumerate() {
            self.check(name, many.then_some(i), v)?;
        }
        Ok(())
    }
}

impl fmt::Display for Range {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let open = if self.lo_open { "(" } else { "[" };
        let close = if self.hi_open { ")" } else { "]" };
        write!(f, "{open}{}, {}{close}", Bound(self.lo), Bound(self.hi))?;
        if !self.unit.is_empty() {
            write!(f, " {}", self.unit)?;
        }
        Ok(())
    }
}

/// A range's end as people write it: `500`, `0.05`, but `1e7` and `1e-4` (not `10000000`
/// and `0.0001`), `inf`.
struct Bound(f64);

impl fmt::Display for Bound {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        let a = x.abs();
        if x.is_finite() && x != 0.0 && !(1e-3..1e6).contains(&a) {
            write!(f, "{x:e}")
        } else {
            write!(f, "{x}")
        }
    }
}

/// The length of the broadcast result of arrays that have length 1 or n.
pub fn broadcast_len(args: &[(&'static str, usize)]) -> Result<usize> {
    let n = args.iter().map(|&(_, l)| l).max().unwrap_or(1);
    for &(name, len) in args {
        if len != 1 && len != n {
            return Err(Error::Length {
                param: Param { name, index: None },
                len,
                expected: n,
            });
        }
    }
    Ok(n)
}

/// Element `i` of a slice broadcast from length 1.
#[inline]
pub fn at(values: &[f64], i: usize) -> f64 {
    if values.len() == 1 {
        values[0]
    } else {
        values[i]
    }
}
