//! Lane groups at the machine's vector width, chosen at run time.
//!
//! The release binary targets baseline x86-64 (SSE2), so code compiled the ordinary way
//! uses 4-lane vectors at most. The fused step ([`super::fused`]) is written once, generic
//! over the instruction set `S`, on [`F`] (a vector of `S`'s width whose operations are
//! `S`'s instructions), and [`dispatch`] runs it inside a function compiled for the widest
//! instruction set the CPU has: AVX-512 (16 lanes), AVX2 (8), SSE4.2 or NEON (4), or none
//! (1). `pulp` does the detection and holds the one `unsafe` that entering such a function
//! needs; this crate stays `forbid(unsafe_code)`. (Plain `[f32; W]` arrays left to LLVM's
//! vectorizer were tried first: it kept much of the 4- and 8-lane code scalar.)
//!
//! Every width computes the same bits: each lane does the scalar code's operations in the
//! scalar code's order, Rust never contracts `a * b + c` into a fused multiply-add, and
//! `sqrt` and `/` are correctly rounded at every width.

use std::fmt;
use std::ops::{Add, AddAssign, BitAnd, BitOr, Div, Mul, Neg, Sub};

use pulp::Simd as Isa;

/// A vector of `S`'s width (`S::F32_LANES` lanes of `f32`). Each operation is the
/// instruction set's lane-wise IEEE operation (through `pulp`), so each lane computes
/// what scalar code computes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct F<S: Isa>(S::f32s, S);

/// A lane mask of `S`'s width (a vector of all-ones lanes, or an AVX-512 mask register).
#[derive(Clone, Copy, Debug)]
pub(crate) struct M<S: Isa>(S::m32s, S);

impl<S: Isa> F<S> {
    /// Every lane `v`.
    #[inline(always)]
    pub fn splat(s: S, v: f32) -> Self {
        Self(s.splat_f32s(v), s)
    }

    /// `sl[at .. at + lanes]`.
    #[inline(always)]
    pub fn load(s: S, sl: &[f32], at: usize) -> Self {
        Self(bytemuck::pod_read_unaligned(bytemuck::cast_slice(&sl[at..at + S::F32_LANES])), s)
    }

    /// Writes the lanes to `sl[at .. at + lanes]`.
    #[inline(always)]
    pub fn store(self, sl: &mut [f32], at: usize) {
        bytemuck::cast_slice_mut::<f32, u8>(&mut sl[at..at + S::F32_LANES])
            .copy_from_slice(bytemuck::bytes_of(&self.0));
    }

    /// The lanes.
    #[inline(always)]
    pub fn lanes(&self) -> &[f32] {
        bytemuck::cast_slice(std::slice::from_ref(&self.0))
    }

    /// The lanes, to change.
    #[inline(always)]
    pub fn lanes_mut(&mut self) -> &mut [f32] {
        bytemuck::cast_slice_mut(std::slice::from_mut(&mut self.0))
    }

    /// Lane `k`.
    #[inline(always)]
    pub fn lane(&self, k: usize) -> f32 {
        self.lanes()[k]
    }

    /// Sets lane `k`.
    #[inline(always)]
    pub fn set_lane(&mut self, k: usize, v: f32) {
        self.lanes_mut()[k] = v;
    }

    /// Lane-wise square root.
    #[inline(always)]
    pub fn sqrt(self) -> Self {
        Self(self.1.sqrt_f32s(self.0), self.1)
    }

    /// Lane-wise maximum (of values that are not NaN).
    #[inline(always)]
    pub fn max(self, o: Self) -> Self {
        Self(self.1.max_f32s(self.0, o.0), self.1)
    }

    /// `self > o`.
    #[inline(always)]
    pub fn gt(self, o: Self) -> M<S> {
        M(self.1.greater_than_f32s(self.0, o.0), self.1)
    }

    /// `self < o`.
    #[inline(always)]
    pub fn lt(self, o: Self) -> M<S> {
        M(self.1.less_than_f32s(self.0, o.0), self.1)
    }

    /// `self == o`.
    #[inline(always)]
    pub fn eq(self, o: Self) -> M<S> {
        M(self.1.equal_f32s(self.0, o.0), self.1)
    }

    /// `a` where `m`, else `b`.
    #[inline(always)]
    pub fn select(m: M<S>, a: Self, b: Self) -> Self {
        Self(m.1.select_f32s(m.0, a.0, b.0), m.1)
    }
}

/// The starts of the lane groups that cover `lo .. hi`: every `lanes`, the last one moved
/// back to end at `hi` (it recomputes a few lanes, which write what they wrote before:
/// each lane depends on its inputs only). None when the range is narrower than a group.
#[inline(always)]
pub(crate) fn groups(lo: usize, hi: usize, lanes: usize) -> impl Iterator<Item = usize> {
    let end = if hi >= lo + lanes { hi } else { lo };
    (lo..end).step_by(lanes).map(move |i| i.min(hi - lanes))
}

/// What [`groups`] leaves to scalar code: all of `lo .. hi` when it is narrower than a
/// group, else nothing.
#[inline(always)]
pub(crate) fn leftover(lo: usize, hi: usize, lanes: usize) -> std::ops::Range<usize> {
    if hi >= lo + lanes { hi..hi } else { lo..hi }
}

impl<S: Isa> M<S> {
    /// Every lane `v`.
    #[inline(always)]
    pub fn splat(s: S, v: bool) -> Self {
        let z = s.splat_f32s(0.0);
        Self(if v { s.equal_f32s(z, z) } else { s.less_than_f32s(z, z) }, s)
    }

    /// The set lanes as bits (lane `k` is bit `k`).
    #[inline(always)]
    pub fn bits(self) -> u32 {
        let s = self.1;
        let one = F::splat(s, 1.0);
        let f = F::select(self, one, F::splat(s, 0.0));
        f.lanes().iter().enumerate().fold(0, |b, (k, &v)| b | (((v != 0.0) as u32) << k))
    }

    /// Whether any lane is set.
    #[inline(always)]
    pub fn any(self) -> bool {
        self.1.first_true_m32s(self.0) < S::F32_LANES
    }
}

macro_rules! lanewise {
    ($tr:ident, $f:ident, $op:ident) => {
        impl<S: Isa> $tr for F<S> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                Self(self.1.$op(self.0, o.0), self.1)
            }
        }
    };
}
lanewise!(Add, add, add_f32s);
lanewise!(Sub, sub, sub_f32s);
lanewise!(Mul, mul, mul_f32s);
lanewise!(Div, div, div_f32s);

impl<S: Isa> AddAssign for F<S> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl<S: Isa> Neg for F<S> {
    type Output = Self;
    /// Flips the sign bit, as scalar negation does.
    #[inline(always)]
    fn neg(self) -> Self {
        Self(self.1.neg_f32s(self.0), self.1)
    }
}

impl<S: Isa> BitAnd for M<S> {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        Self(self.1.and_m32s(self.0, o.0), self.1)
    }
}

impl<S: Isa> BitOr for M<S> {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        Self(self.1.or_m32s(self.0, o.0), self.1)
    }
}

/// An instruction set the fused CPU step can run on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Simd {
    /// x86-64-v4: AVX-512, 16 lanes.
    Avx512,
    /// x86-64-v3: AVX2 (its fused multiply-add unused: see the module notes), 8 lanes.
    Avx2,
    /// x86-64-v2: SSE4.2, 4 lanes.
    Sse42,
    /// aarch64: NEON, 4 lanes.
    Neon,
    /// One lane: a CPU with none of the above.
    Scalar,
}

/// The environment variable that picks a narrower instruction set than the widest one
/// the CPU has (`avx512`, `avx2`, `sse4.2`, `neon`, `scalar`), to compare them.
pub const SIMD_ENV: &str = "CLOTHLAB_CPU_SIMD";

/// The environment variable that switches the fused sweep off (`off`; `on` is the
/// default), for the kernel-by-kernel step and its per-kernel timings.
pub const FUSED_ENV: &str = "CLOTHLAB_CPU_FUSED";

/// Whether `CLOTHLAB_CPU_FUSED` leaves the fused sweep on; a value other than `on` or
/// `off` is refused with a line that says so.
pub fn fused_from_env() -> Result<bool, String> {
    match std::env::var(FUSED_ENV).as_deref() {
        Err(_) | Ok("" | "on") => Ok(true),
        Ok("off") => Ok(false),
        Ok(v) => Err(format!("{FUSED_ENV}={v}: expected on or off")),
    }
}

impl Simd {
    /// Every instruction set, widest first.
    pub const ALL: [Simd; 5] = [Simd::Avx512, Simd::Avx2, Simd::Sse42, Simd::Neon, Simd::Scalar];

    /// Lanes per vector.
    pub fn lanes(self) -> usize {
        match self {
            Simd::Avx512 => 16,
            Simd::Avx2 => 8,
            Simd::Sse42 | Simd::Neon => 4,
            Simd::Scalar => 1,
        }
    }

    /// The name `CLOTHLAB_CPU_SIMD` takes.
    pub fn name(self) -> &'static str {
        match self {
            Simd::Avx512 => "avx512",
            Simd::Avx2 => "avx2",
            Simd::Sse42 => "sse4.2",
            Simd::Neon => "neon",
            Simd::Scalar => "scalar",
        }
    }

    /// Whether this CPU can run it.
    pub fn available(self) -> bool {
        match self {
            #[cfg(target_arch = "x86_64")]
            Simd::Avx512 => pulp::x86::V4::try_new().is_some(),
            #[cfg(target_arch = "x86_64")]
            Simd::Avx2 => pulp::x86::V3::try_new().is_some(),
            #[cfg(target_arch = "x86_64")]
            Simd::Sse42 => pulp::x86::V2::try_new().is_some(),
            #[cfg(target_arch = "aarch64")]
            Simd::Neon => pulp::aarch64::Neon::try_new().is_some(),
            Simd::Scalar => true,
            #[allow(unreachable_patterns)]
            _ => false,
        }
    }

    /// The widest this CPU has.
    pub fn detect() -> Simd {
        Simd::ALL.into_iter().find(|s| s.available()).unwrap_or(Simd::Scalar)
    }

    /// The widest this CPU has, or the one `CLOTHLAB_CPU_SIMD` names; a name that is not
    /// one, or one this CPU lacks, is refused with a line that says so.
    pub fn from_env() -> Result<Simd, String> {
        match std::env::var(SIMD_ENV) {
            Err(_) => Ok(Simd::detect()),
            Ok(v) if v.is_empty() || v == "auto" => Ok(Simd::detect()),
            Ok(v) => {
                let names: Vec<&str> = Simd::ALL.iter().map(|s| s.name()).collect();
                let s = Simd::ALL.into_iter().find(|s| s.name() == v).ok_or_else(|| {
                    format!("{SIMD_ENV}={v}: not an instruction set; expected auto or one of {}", names.join(", "))
                })?;
                if s.available() {
                    Ok(s)
                } else {
                    Err(format!("{SIMD_ENV}={v}: this CPU has no {v}; its widest is {}", Simd::detect()))
                }
            }
        }
    }
}

impl fmt::Display for Simd {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let isa = match self {
            Simd::Avx512 => "AVX-512",
            Simd::Avx2 => "AVX2",
            Simd::Sse42 => "SSE4.2",
            Simd::Neon => "NEON",
            Simd::Scalar => "scalar",
        };
        let s = if self.lanes() == 1 { "" } else { "s" };
        write!(f, "{isa}, {} lane{s}", self.lanes())
    }
}

/// Work generic over the instruction set.
pub(crate) trait Lanewise {
    /// What it returns.
    type Out;
    /// Runs on `s`.
    fn run<S: Isa>(self, s: S) -> Self::Out;
}

/// Runs `job` compiled for `simd` (the scalar fallback where this CPU lacks it).
/// Everything `job.run` calls must be `#[inline(always)]` to be compiled for `simd` too.
#[inline(always)]
pub(crate) fn dispatch<K: Lanewise>(simd: Simd, job: K) -> K::Out {
    struct Job<K>(K);
    impl<K: Lanewise> pulp::WithSimd for Job<K> {
        type Output = K::Out;
        #[inline(always)]
        fn with_simd<S: Isa>(self, s: S) -> K::Out {
            self.0.run(s)
        }
    }
    let job = Job(job);
    #[cfg(target_arch = "x86_64")]
    match simd {
        Simd::Avx512 => {
            if let Some(s) = pulp::x86::V4::try_new() {
                return Isa::vectorize(s, job);
            }
        }
        Simd::Avx2 => {
            if let Some(s) = pulp::x86::V3::try_new() {
                return Isa::vectorize(s, job);
            }
        }
        Simd::Sse42 => {
            if let Some(s) = pulp::x86::V2::try_new() {
                return Isa::vectorize(s, job);
            }
        }
        Simd::Neon | Simd::Scalar => {}
    }
    #[cfg(target_arch = "aarch64")]
    if let (Simd::Neon, Some(s)) = (simd, pulp::aarch64::Neon::try_new()) {
        return Isa::vectorize(s, job);
    }
    let _ = simd;
    Isa::vectorize(pulp::Scalar::new(), job)
}
