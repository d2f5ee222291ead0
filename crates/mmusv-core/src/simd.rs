//! Run-time CPU feature dispatch, so one portable binary (a wheel built for any x86-64) still uses AVX2.
//!
//! Hot loops are written once as `#[inline(always)]` generic code over plain arrays; [`dispatch!`] compiles
//! the call twice, once inside a function with `#[target_feature(enable = "avx2,fma")]` and once for the
//! baseline, and picks one at run time. Rust never contracts `a * b + c` into a fused multiply-add on its own,
//! so both versions round identically and give bit-identical results (tests check this with
//! [`set_portable`]).

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

/// Defines `$name` (calling `$body` through its AVX2 twin where the CPU allows) from one body.
///
/// ```ignore
/// dispatch! {
///     /// Docs.
///     pub(crate) fn trace(scene: &Scene, out: &mut [f32]) { /* inline(always) calls */ }
/// }
/// ```
#[macro_export]
#[doc(hidden)]
macro_rules! dispatch {
    ($(#[$m:meta])* $vis:vis fn $name:ident($($arg:ident : $ty:ty),* $(,)?) $(-> $ret:ty)? $body:block) => {
        $(#[$m])*
        $vis fn $name($($arg: $ty),*) $(-> $ret)? {
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx2,fma")]
                fn avx2($($arg: $ty),*) $(-> $ret)? $body
                if $crate::simd::avx2() {
                    #[allow(unsafe_code)]
                    // SAFETY: `avx2()` checked at run time that this CPU has AVX2 and FMA.
                    return unsafe { avx2($($arg),*) };
                }
            }
            #[inline(always)]
            fn portable($($arg: $ty),*) $(-> $ret)? $body
            portable($($arg),*)
        }
    };
}
