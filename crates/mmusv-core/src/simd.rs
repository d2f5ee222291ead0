//! Run-time CPU feature dispatch, so one portable binary (a wheel built for any x86-64) still uses AVX2.
//!
//! Hot loops are written once as `#[inline(always)]` generic code over plain arrays. Two macros compile them
//! for each instruction-set level:
//!
//! * `dispatch!` defines an entry point: its body is compiled twice, once inside a function with
//!   `#[target_feature(enable = "avx2,fma")]` and once for the baseline, and one is picked at run time.
//! * `kernel!` defines a kernel called from inside such bodies (a mesh's BVH walk, say): one out-of-line copy
//!   per level, chosen at compile time by the caller's [`Level`] token. Kernels keep every caller's code small —
//!   a walk inlined into each of its call sites is compiled (and cached) once per site — without giving up the
//!   caller's level.
//!
//! A [`Level`] token is a zero-sized proof of the level the code holding it may use: [`Portable`] anywhere,
//! [`Avx2`] only after the CPU was checked ([`Avx2::detect`]). Rust never contracts `a * b + c` into a fused
//! multiply-add on its own, so every level rounds identically and gives bit-identical results (tests check
//! this with [`set_portable`]).

use std::sync::atomic::{AtomicU8, Ordering};

const UNKNOWN: u8 = 0;
const PORTABLE: u8 = 1;
const AVX2: u8 = 2;

static LEVEL: AtomicU8 = AtomicU8::new(UNKNOWN);

/// Whether the AVX2 + FMA versions run on this CPU (detected once; `MMUSV_SIMD=portable` in the environment
/// forces the baseline versions).
#[inline]
pub fn avx2() -> bool {
    match LEVEL.load(Ordering::Relaxed) {
        UNKNOWN => {
            let level = detect();
            LEVEL.store(level, Ordering::Relaxed);
            level == AVX2
        }
        level => level == AVX2,
    }
}

fn detect() -> u8 {
    if std::env::var("MMUSV_SIMD").is_ok_and(|v| v.eq_ignore_ascii_case("portable")) {
        return PORTABLE;
    }
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        return AVX2;
    }
    PORTABLE
}

/// Forces the baseline versions (`true`) or re-detects the CPU (`false`): for tests that compare both paths.
pub fn set_portable(portable: bool) {
    LEVEL.store(if portable { PORTABLE } else { detect() }, Ordering::Relaxed);
}

/// The dispatch level in words (`"avx2"` or `"portable"`), for benchmark reports.
pub fn level_name() -> &'static str {
    if avx2() {
        "avx2"
    } else {
        "portable"
    }
}

mod sealed {
    pub trait Sealed {}
}

/// An instruction-set level, as a zero-sized token passed by value to the code that may use it (see the module
/// docs). Sealed: the levels are [`Portable`] and [`Avx2`].
pub trait Level: Copy + Send + Sync + std::fmt::Debug + sealed::Sealed + 'static {
    /// Whether code holding this token may use AVX2 and FMA instructions.
    const AVX2: bool;
}

/// The baseline level: runs on every CPU.
#[derive(Debug, Clone, Copy, Default)]
pub struct Portable;

/// AVX2 + FMA: a value exists only where the CPU has both ([`Avx2::detect`]).
#[derive(Debug, Clone, Copy)]
pub struct Avx2 {
    _checked: (),
}

impl Avx2 {
    /// The token, when this CPU runs the AVX2 versions ([`avx2`]).
    #[inline(always)]
    pub fn detect() -> Option<Self> {
        avx2().then_some(Avx2 { _checked: () })
    }

    /// The token without a check.
    ///
    /// # Safety
    /// Only where [`avx2`] returned `true` (as inside [`dispatch!`]'s AVX2 branch).
    #[doc(hidden)]
    #[inline(always)]
    #[allow(unsafe_code)]
    pub unsafe fn assume() -> Self {
        Avx2 { _checked: () }
    }
}

impl sealed::Sealed for Portable {}
impl sealed::Sealed for Avx2 {}
impl Level for Portable {
    const AVX2: bool = false;
}
impl Level for Avx2 {
    const AVX2: bool = true;
}

/// Defines `$name` (calling `$body` through its AVX2 twin where the CPU allows) from one body. With `[lv]`
/// after the name, the body sees the level token as `lv` ([`Avx2`] or [`Portable`]) to hand to [`kernel!`]s.
///
/// ```ignore
/// dispatch! {
///     /// Docs.
///     pub(crate) fn trace[lv](scene: &Scene, out: &mut [f32]) { /* inline(always) calls, kernels get `lv` */ }
/// }
/// ```
#[macro_export]
#[doc(hidden)]
macro_rules! dispatch {
    ($(#[$m:meta])* $vis:vis fn $name:ident $([$lv:ident])? ($($arg:ident : $ty:ty),* $(,)?) $(-> $ret:ty)? $body:block) => {
        $(#[$m])*
        $vis fn $name($($arg: $ty),*) $(-> $ret)? {
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx2,fma")]
                fn avx2($($arg: $ty),*) $(-> $ret)? {
                    $(
                        #[allow(unsafe_code)]
                        // SAFETY: only called below, after `avx2()` checked this CPU.
                        let $lv = unsafe { $crate::simd::Avx2::assume() };
                    )?
                    $body
                }
                if $crate::simd::avx2() {
                    #[allow(unsafe_code)]
                    // SAFETY: `avx2()` checked at run time that this CPU has AVX2 and FMA.
                    return unsafe { avx2($($arg),*) };
                }
            }
            #[inline(always)]
            fn portable($($arg: $ty),*) $(-> $ret)? {
                $(let $lv = $crate::simd::Portable;)?
                $body
            }
            portable($($arg),*)
        }
    };
}

/// Defines the kernel `$name<L: Level>(lv: L, args…)`: `$body` compiled once per level, out of line, and the
/// copy for the caller's token `lv` called (the choice is made at compile time). With `[lv]` after the name,
/// the body sees its own token as `lv`. Arguments are plain (no `Self`, no outer generics).
///
/// ```ignore
/// kernel! {
///     /// Docs.
///     pub(crate) fn walk(mesh: &Mesh, ray: &RayPrep) -> f32 { /* inline(always) calls */ }
/// }
/// // caller, inside a dispatch! body with token `lv`:  walk(lv, mesh, ray)
/// ```
#[macro_export]
#[doc(hidden)]
macro_rules! kernel {
    ($(#[$m:meta])* $vis:vis fn $name:ident $([$lv:ident])? ($($arg:ident : $ty:ty),* $(,)?) $(-> $ret:ty)? $body:block) => {
        $(#[$m])*
        #[inline(always)]
        $vis fn $name<L: $crate::simd::Level>(_level: L, $($arg: $ty),*) $(-> $ret)? {
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx2,fma")]
                #[inline(never)]
                fn avx2($($arg: $ty),*) $(-> $ret)? {
                    $(
                        #[allow(unsafe_code)]
                        // SAFETY: only called below, for a caller holding an `Avx2` token.
                        let $lv = unsafe { $crate::simd::Avx2::assume() };
                    )?
                    $body
                }
                if L::AVX2 {
                    #[allow(unsafe_code)]
                    // SAFETY: `L` is `Avx2`, and an `Avx2` token (`_level`) exists only on a CPU with AVX2 and FMA.
                    return unsafe { avx2($($arg),*) };
                }
            }
            #[inline(never)]
            fn portable($($arg: $ty),*) $(-> $ret)? {
                $(let $lv = $crate::simd::Portable;)?
                $body
            }
            portable($($arg),*)
        }
    };
}
