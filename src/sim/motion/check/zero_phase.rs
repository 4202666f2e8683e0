//! A zero-phase low-pass filter for positions about to be differentiated twice.
//!
//! A second-order Butterworth section run forward and then backward (the "filtfilt" of
//! biomechanics): the magnitude response is the square of one pass (−6 dB at the cutoff,
//! fourth-order roll-off) and the phase is zero, so a smoothed acceleration does not lag
//! the hand forces recorded at the same frame. Differentiating twice multiplies noise at
//! frequency f by (2πf)²; human movement has little above about 6 Hz (Winter,
//! *Biomechanics and Motor Control of Human Movement*, 4th ed., 2009, §3.4: 6 Hz for gait
//! marker data), which is the check's default cutoff.
//!
//! Ends: the signal is extended by its odd reflection about each end point (the extension
//! continues its slope), and each pass starts in the steady state of its first sample.

/// Default cutoff of [`low_pass_zero_phase`] in the data check, Hz.
pub const DEFAULT_CUTOFF_HZ: f64 = 6.0;

/// The highest cutoff a rate allows, as a fraction of the sample rate (below Nyquist, with
/// room for the bilinear transform's warping).
pub const MAX_CUTOFF_FRACTION: f64 = 0.4;

/// Coefficients of a second-order Butterworth low-pass (bilinear transform, pre-warped):
/// `([b0, b1, b2], [a1, a2])` for `y = b·x − a·y_past`.
fn butterworth2(cutoff_hz: f64, rate_hz: f64) -> ([f64; 3], [f64; 2]) {
    let k = (std::f64::consts::PI * cutoff_hz / rate_hz).tan();
    let s2 = std::f64::consts::SQRT_2;
    let norm = 1.0 / (1.0 + s2 * k + k * k);
    let b0 = k * k * norm;
    (
        [b0, 2.0 * b0, b0],
        [2.0 * (k * k - 1.0) * norm, (1.0 - s2 * k + k * k) * norm],
    )
}

/// One causal pass, started in the steady state of `x[0]` (unit gain at DC).
fn pass(x: &[f64], b: &[f64; 3], a: &[f64; 2]) -> Vec<f64> {
    let x0 = x.first().copied().unwrap_or(0.0);
    let (mut x1, mut x2, mut y1, mut y2) = (x0, x0, x0, x0);
    x.iter()
        .map(|&xn| {
            let y = b[0] * xn + b[1] * x1 + b[2] * x2 - a[0] * y1 - a[1] * y2;
            (x2, x1, y2, y1) = (x1, xn, y1, y);
            y
        })
        .collect()
}

/// `signal` sampled at `rate_hz`, low-passed at `cutoff_hz` with zero phase. The cutoff is
/// limited to [`MAX_CUTOFF_FRACTION`] of the rate; signals of fewer than 3 samples are
/// returned as they are.
pub fn low_pass_zero_phase(signal: &[f64], cutoff_hz: f64, rate_hz: f64) -> Vec<f64> {
    let n = signal.len();
    if n < 3 {
        return signal.to_vec();
    }
    let cutoff = cutoff_hz.min(MAX_CUTOFF_FRACTION * rate_hz);
    let (b, a) = butterworth2(cutoff, rate_hz);
    // About three time constants of the filter, at most the signal's length.
    let pad = ((3.0 * rate_hz / cutoff).ceil() as usize).min(n - 1);
    let (first, last) = (signal[0], signal[n - 1]);
    let mut extended = Vec::with_capacity(n + 2 * pad);
    extended.extend((1..=pad).rev().map(|k| 2.0 * first - signal[k]));
    extended.extend_from_slice(signal);
    extended.extend((1..=pad).map(|k| 2.0 * last - signal[n - 1 - k]));
    let mut y = pass(&extended, &b, &a);
    y.reverse();
    let mut y = pass(&y, &b, &a);
    y.reverse();
    y[pad..pad + n].to_vec()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sine(f_hz: f64, rate: f64, n: usize) -> Vec<f64> {
        (0..n)
            .map(|k| (2.0 * std::f64::consts::PI * f_hz * k as f64 / rate).sin())
            .collect()
    }

    #[test]
    fn slow_motion_passes_unchanged_and_in_phase() {
        let x = sine(0.5, 50.0, 500);
        let y = low_pass_zero_phase(&x, 6.0, 50.0);
        let worst = x
            .iter()
            .zip(&y)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst < 0.01, "0.5 Hz changed by {worst}");
    }

    #[test]
    fn noise_above_the_cutoff_is_removed() {
        let y = low_pass_zero_phase(&sine(20.0, 50.0, 500), 6.0, 50.0);
        let mid = &y[100..400];
        let peak = mid.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(peak < 0.02, "20 Hz kept at {peak}");
    }

    #[test]
    fn the_cutoff_halves_the_amplitude() {
        // Two passes of a Butterworth section: |H|² = 1/2 at the cutoff.
        let y = low_pass_zero_phase(&sine(6.0, 100.0, 2000), 6.0, 100.0);
        let peak = y[500..1500].iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!((peak - 0.5).abs() < 0.02, "gain at cutoff {peak}");
    }

    #[test]
    fn a_ramp_keeps_its_ends() {
        let x: Vec<f64> = (0..40).map(|k| 0.1 * k as f64).collect();
        let y = low_pass_zero_phase(&x, 6.0, 50.0);
        assert!(x.iter().zip(&y).all(|(a, b)| (a - b).abs() < 1e-6));
    }
}
