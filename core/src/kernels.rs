//! The kernel set: which compiled instance of the arithmetic kernels a process runs.
//!
//! The hot kernels (the banded Cholesky's factor and solves, the stretching's and
//! bending's lane forms, the batched step, the band updates) exist twice: a plain
//! instance any processor runs, and one compiled for AVX2 with fused multiply-add
//! (one rounding per `a·b + c` instead of two). The two give results that differ at
//! round-off, so a result is bit-identical only to results of the same set. The set is
//! chosen once per process, the first time any kernel asks ([`active`]), from the
//! environment variable [`ENV`] (`SPLINEROD_KERNELS`):
//!
//! | Value | Set |
//! |---|---|
//! | unset, empty or `auto` | the fastest this processor has: `avx2-fma` on x86-64 processors with AVX2 and FMA, `portable` otherwise |
//! | `portable` | the plain kernels, on any processor |
//! | `avx2-fma` | the fused kernels; an error where the processor lacks them |
//!
//! Any other value (or `avx2-fma` on a processor without AVX2 and FMA) is an error: the
//! library then runs the fastest set and reports the error through [`setting_error`],
//! which the `splinerod` command line turns into exit code 2 before it does anything.
//! [`crate::lanes::wide`] is the one switch every kernel branches on; results (JSON
//! `kernels`), checkpoints and shards record [`name`].

use std::sync::OnceLock;

/// The environment variable that chooses the kernel set.
pub const ENV: &str = "SPLINEROD_KERNELS";

/// A compiled instance of the arithmetic kernels (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum KernelSet {
    /// The plain kernels: any processor, the same bits everywhere.
    Portable,
    /// The kernels compiled for AVX2 with fused multiply-add (x86-64 only).
    Avx2Fma,
}

impl KernelSet {
    /// Its name as results record it: `"portable"` or `"avx2-fma"`.
    pub fn name(self) -> &'static str {
        match self {
            KernelSet::Portable => "portable",
            KernelSet::Avx2Fma => "avx2-fma",
        }
    }

    /// Whether this processor can run the set.
    pub fn available(self) -> bool {
        match self {
            KernelSet::Portable => true,
            KernelSet::Avx2Fma => avx2_fma(),
        }
    }

    /// The fastest set this processor runs.
    pub fn fastest() -> KernelSet {
        if avx2_fma() {
            KernelSet::Avx2Fma
        } else {
            KernelSet::Portable
        }
    }
}

#[cfg(target_arch = "x86_64")]
fn avx2_fma() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

#[cfg(not(target_arch = "x86_64"))]
fn avx2_fma() -> bool {
    false
}

/// The set chosen for `value` (of [`ENV`]; `None` when unset) and, when the value is
/// not understood or asks for a set this processor lacks, the error message (naming
/// [`ENV`] and the value); the fastest set runs then. Pure: [`active`] applies it once
/// to the environment.
pub fn choose(value: Option<&std::ffi::OsStr>) -> (KernelSet, Option<String>) {
    let fastest = KernelSet::fastest();
    let Some(value) = value else {
        return (fastest, None);
    };
    let expected =
        "expected \"auto\" (the fastest set this processor has), \"portable\" or \"avx2-fma\"";
    let Some(text) = value.to_str() else {
        let shown = value.to_string_lossy();
        return (fastest, Some(format!("{ENV}=\"{shown}\": {expected}")));
    };
    match text.trim() {
        "" | "auto" => (fastest, None),
        "portable" => (KernelSet::Portable, None),
        "avx2-fma" if KernelSet::Avx2Fma.available() => (KernelSet::Avx2Fma, None),
        "avx2-fma" => {
            let reason = "this processor lacks AVX2 or FMA; use \"portable\" or \"auto\"";
            (fastest, Some(format!("{ENV}=\"{text}\": {reason}")))
        }
        _ => (fastest, Some(format!("{ENV}=\"{text}\": {expected}"))),
    }
}

fn choice() -> &'static (KernelSet, Option<String>) {
    static CHOICE: OnceLock<(KernelSet, Option<String>)> = OnceLock::new();
    CHOICE.get_or_init(|| choose(std::env::var_os(ENV).as_deref()))
}

/// The kernel set this process runs, chosen once from [`ENV`] (module docs).
#[inline]
pub fn active() -> KernelSet {
    choice().0
}

/// The name of the kernel set this process runs (`"portable"` or `"avx2-fma"`): what
/// results, checkpoints and shards record.
pub fn name() -> &'static str {
    active().name()
}

/// The error of [`ENV`]'s value, if it was not understood (the fastest set runs
/// instead); `None` when the setting is valid or unset.
pub fn setting_error() -> Option<&'static str> {
    choice().1.as_deref()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ffi::OsStr;

    #[test]
    fn values_choose_a_set_or_name_the_variable_and_the_value() {
        let fastest = KernelSet::fastest();
        assert_eq!(choose(None), (fastest, None));
        assert_eq!(choose(Some(OsStr::new("auto"))), (fastest, None));
        assert_eq!(choose(Some(OsStr::new(""))), (fastest, None));
        assert_eq!(
            choose(Some(OsStr::new("portable"))),
            (KernelSet::Portable, None)
        );
        let (set, error) = choose(Some(OsStr::new("fast")));
        assert_eq!(set, fastest);
        let error = error.expect("an error");
        assert!(error.contains("SPLINEROD_KERNELS") && error.contains("\"fast\""));
        let (set, error) = choose(Some(OsStr::new("avx2-fma")));
        if KernelSet::Avx2Fma.available() {
            assert_eq!((set, error), (KernelSet::Avx2Fma, None));
        } else {
            assert!(error.expect("an error").contains("lacks"));
        }
        assert_eq!(KernelSet::Portable.name(), "portable");
        assert_eq!(KernelSet::Avx2Fma.name(), "avx2-fma");
        assert!(active().available());
        assert_eq!(name(), active().name());
    }
}
