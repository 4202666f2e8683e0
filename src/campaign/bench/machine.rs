//! The machine a measurement was taken on, as every `thorarena bench` prints it first: a
//! figure without its CPU is not a figure (a rapier step measured 245 µs on one 2-core
//! host and 390 µs on another), and the ISA level says which network kernels ran.

use std::fmt;

/// CPU model, logical cores, the psABI level of the instruction sets, and the kernels a
/// network runs on here.
#[derive(Debug, Clone)]
pub struct Machine {
    /// `model name` of `/proc/cpuinfo` (the first core), or `unknown`.
    pub cpu_model: String,
    /// Cores this process may run on.
    pub cores: usize,
    /// `x86-64-v4` (AVX-512), `-v3` (AVX2, FMA), `-v2`, `-v1`, or the architecture's name
    /// elsewhere.
    pub isa_level: &'static str,
    /// What [`crate::policy::network_kernels::network_kernels`] chose.
    pub network_kernels: String,
}

impl Machine {
    /// This machine.
    pub fn this() -> Self {
        let cpu_model = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|s| {
                s.lines()
                    .find(|l| l.starts_with("model name"))
                    .and_then(|l| l.split_once(':'))
                    .map(|(_, v)| v.trim().to_string())
            })
            .unwrap_or_else(|| "unknown".into());
        Self {
            cpu_model,
            cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
            isa_level: isa_level(),
            network_kernels: crate::policy::network_kernels::network_kernels()
                .isa
                .clone(),
        }
    }
}

impl fmt::Display for Machine {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "machine: {}, {} cores, {}; networks on {}",
            self.cpu_model, self.cores, self.isa_level, self.network_kernels
        )
    }
}

#[cfg(target_arch = "x86_64")]
fn isa_level() -> &'static str {
    use std::arch::is_x86_feature_detected as has;
    if has!("avx512f")
        && has!("avx512bw")
        && has!("avx512cd")
        && has!("avx512dq")
        && has!("avx512vl")
    {
        "x86-64-v4"
    } else if has!("avx2") && has!("fma") && has!("bmi2") && has!("movbe") {
        "x86-64-v3"
    } else if has!("sse4.2") && has!("popcnt") && has!("ssse3") {
        "x86-64-v2"
    } else {
        "x86-64-v1"
    }
}

#[cfg(not(target_arch = "x86_64"))]
fn isa_level() -> &'static str {
    std::env::consts::ARCH
}
