//! Which CPU kernel runs: the same functions compiled for different vector
//! instructions, chosen by what the CPU has.

/// Panics unless this CPU runs `kernel`: what makes `with_simd` safe for
/// the `_with` entry points.
pub(super) fn check_runs(kernel: CpuKernel) {
    if let Some(missing) = kernel.missing() {
        panic!("the {} CPU kernel needs {missing}", kernel.name());
    }
}

/// `LAMBERT_CPU_KERNEL`: a narrower CPU kernel than the CPU's widest, by
/// name (`CpuKernel::select`); read by the front ends, not the library.
pub const CPU_KERNEL_ENV: &str = "LAMBERT_CPU_KERNEL";

/// The kernel of this process (`CpuKernel::active`).
static ACTIVE: std::sync::OnceLock<CpuKernel> = std::sync::OnceLock::new();

/// The CPU kernels: the same functions compiled for different vector
/// instructions. Each runs the same IEEE operations, so each gives the
/// portable kernel's results bit for bit (tests/cpu_kernels.rs checks that
/// on every kernel the test machine can run).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum CpuKernel {
    /// Plain Rust (SSE2 on x86-64; NEON or none elsewhere).
    Portable,
    /// AVX2 with FMA (x86 since 2013), and the bit instructions every
    /// such CPU has (BMI1/2, LZCNT, POPCNT: x86-64-v3's): the 8-lane slab
    /// test in one register, and fused multiply-adds (without FMA, each is
    /// a library call per lane: about 4× slower traversal); without
    /// POPCNT, a count of set bits is a dozen instructions.
    Avx2Fma,
    /// AVX-512 (F, VL, DQ, BW, with BMI1/2 and LZCNT; compiled without
    /// POPCNT, which made the Python binding's camera rays 4% slower on a
    /// Zen 4, though the CPU must have it): AVX2's kernel with
    /// mask registers and embedded broadcasts, and incoherent rays order
    /// their entered children in vector registers (`push_sorted_zmm`).
    Avx512,
}

impl CpuKernel {
    pub const ALL: [CpuKernel; 3] = [CpuKernel::Portable, CpuKernel::Avx2Fma, CpuKernel::Avx512];

    /// The name `CPU_KERNEL_ENV` and `lambert info` use.
    pub fn name(self) -> &'static str {
        match self {
            CpuKernel::Portable => "portable",
            CpuKernel::Avx2Fma => "avx2+fma",
            CpuKernel::Avx512 => "avx-512",
        }
    }

    /// What this CPU lacks for the kernel, or None when it can run it.
    pub fn missing(self) -> Option<&'static str> {
        #[cfg(target_arch = "x86_64")]
        {
            use std::is_x86_feature_detected as has;
            let bits = has!("bmi1") && has!("bmi2") && has!("lzcnt") && has!("popcnt");
            let avx2_fma = has!("avx2") && has!("fma") && bits;
            match self {
                CpuKernel::Portable => None,
                CpuKernel::Avx2Fma => {
                    (!avx2_fma).then_some("AVX2 and FMA with BMI1, BMI2, LZCNT and POPCNT")
                }
                CpuKernel::Avx512 => {
                    let avx512 =
                        has!("avx512f") && has!("avx512vl") && has!("avx512dq") && has!("avx512bw");
                    (!(avx2_fma && avx512))
                        .then_some("AVX-512 F/VL/DQ/BW with BMI1, BMI2, LZCNT and POPCNT")
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        return match self {
            CpuKernel::Portable => None,
            _ => Some("an x86-64 CPU"),
        };
    }

    /// The widest kernel this CPU runs.
    pub fn detect() -> CpuKernel {
        *CpuKernel::ALL
            .iter()
            .rev()
            .find(|k| k.missing().is_none())
            .unwrap_or(&CpuKernel::Portable)
    }

    /// The kernel this process uses: the one `select` chose, else
    /// `detect`'s. Decided once, at `select` or at the first use.
    pub fn active() -> CpuKernel {
        *ACTIVE.get_or_init(CpuKernel::detect)
    }

    /// The kernel `asked` names (portable, avx2+fma or avx-512, any case;
    /// what a front end read from `CPU_KERNEL_ENV`) where the CPU runs it,
    /// else the widest it has at most that wide; `detect`'s where `asked`
    /// is None or no kernel's name.
    pub fn narrowed_to(asked: Option<&str>) -> CpuKernel {
        let best = CpuKernel::detect();
        asked
            .and_then(|name| {
                CpuKernel::ALL
                    .into_iter()
                    .find(|k| k.name() == name.to_lowercase())
            })
            .map_or(best, |asked| asked.min(best))
    }

    /// Makes `narrowed_to(asked)` the kernel of this process (`active`),
    /// unless one was decided already; returns the active kernel. The front
    /// ends call it first thing, with the environment's `CPU_KERNEL_ENV`.
    pub fn select(asked: Option<&str>) -> CpuKernel {
        *ACTIVE.get_or_init(|| CpuKernel::narrowed_to(asked))
    }

    /// Whether node visits take f32's `Scalar::intersect_boxes_ymm`.
    pub fn ymm_boxes(self) -> bool {
        self >= CpuKernel::Avx2Fma
    }

    /// This kernel at most 256 bits wide where 512-bit instructions cost:
    /// AVX2's for AVX-512 on an Intel CPU. Intel's cores run a 512-bit
    /// instruction with port 1's vector unit off (some at a lower clock
    /// too), and LLVM's AVX-512 code moves the packets' arrays in 512-bit
    /// registers: on a Sapphire Rapids, camera rays traced 1.06–1.08×
    /// faster in AVX2's kernel, the Python binding's 1.04–1.10×
    /// (docs/benchmarks.md). Zen 4 and 5 split a 512-bit instruction into
    /// two 256-bit halves at no cost, and trace camera rays 1.01–1.03×
    /// faster in AVX-512's kernel; incoherent rays keep it everywhere
    /// (its `push_sorted_zmm`: 1.07× on the Intel too).
    pub fn narrow_on_intel(self) -> CpuKernel {
        match self {
            CpuKernel::Avx512 if is_intel() => CpuKernel::Avx2Fma,
            kernel => kernel,
        }
    }

    /// Whether incoherent rays order children with f32's
    /// `Scalar::push_sorted_zmm`.
    pub fn vector_sort(self) -> bool {
        self == CpuKernel::Avx512
    }
}

/// Whether this CPU is Intel's (CPUID's vendor string).
fn is_intel() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        static INTEL: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
        *INTEL.get_or_init(|| {
            let id = std::arch::x86_64::__cpuid(0);
            // "GenuineIntel", in EBX, EDX, ECX.
            [id.ebx, id.edx, id.ecx] == [0x756e_6547, 0x4965_6e69, 0x6c65_746e]
        })
    }
    #[cfg(not(target_arch = "x86_64"))]
    false
}

/// Runs `f` (an `#[inline(always)]` closure) compiled for `kernel`'s vector
/// instructions: the kernel's functions are inlined into it, so they run
/// the same IEEE operations (the same results) in fewer instructions.
///
/// # Safety
/// The CPU must run `kernel` (`CpuKernel::missing` is None).
#[inline(always)]
pub unsafe fn with_simd<R>(kernel: CpuKernel, f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    match kernel {
        CpuKernel::Avx512 => {
            #[target_feature(
                enable = "avx2,fma,avx512f,avx512vl,avx512dq,avx512bw,bmi1,bmi2,lzcnt"
            )]
            fn avx512<R>(f: impl FnOnce() -> R) -> R {
                f()
            }
            // SAFETY: the caller vouches for the features.
            return unsafe { avx512(f) };
        }
        CpuKernel::Avx2Fma => {
            #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
            fn avx2<R>(f: impl FnOnce() -> R) -> R {
                f()
            }
            // SAFETY: the caller vouches for the features.
            return unsafe { avx2(f) };
        }
        CpuKernel::Portable => {}
    }
    let _ = kernel;
    f()
}
