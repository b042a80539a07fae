//! Signal model eq. (33) and the offline signal→distance calibration with
//! its online inverse, eq. (6) (paper §3.2; spec §2.5, §5 items 16-17).

use rand::Rng;
use serde::{Deserialize, Serialize};

/// Tunables of the signal model and of the calibration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    /// Environmental attenuation coefficient m = 0.1 (Table 4, eq. 33).
    pub m: f64,
    /// Target signal power Q = 1e5 (Table 4, eq. 33).
    pub q: f64,
    /// Standard deviation of the noise η ~ N(0, 1) (paper §5, eq. 33).
    pub noise_sigma: f64,
    /// Target-signal sensing radius L_T = 100; no signal beyond (Table 4, eq. 1).
    pub l_t: f64,
    /// Nearest calibration distance: 1 (paper §3.2 "(1, L_T)").
    pub d_min: f64,
    /// Number of calibration distances ς (not given): 100 evenly spaced in
    /// [d_min, L_T]. [chosen] spec §5 item 16.
    pub n_distances: usize,
    /// Repeated measurements averaged per distance: 100 (paper §3.2).
    pub repeats: usize,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            m: 0.1,
            q: 1e5,
            noise_sigma: 1.0,
            l_t: 100.0,
            d_min: 1.0,
            n_distances: 100,
            repeats: 100,
        }
    }
}

/// One N(0,1) draw by the Box–Muller transform (rand 0.8 has no normal
/// distribution without extra crates). Consumes exactly two uniforms.
pub fn standard_normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    let u1: f64 = 1.0 - rng.gen::<f64>(); // (0, 1]
    let u2: f64 = rng.gen::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Noise-free attenuation G(T_d) = m·Q / T_d² inside L_T, 0 beyond (eq. 33).
pub fn signal_noise_free(d: f64, p: &Params) -> f64 {
    if d <= p.l_t {
        p.m * p.q / (d * d)
    } else {
        0.0
    }
}

/// One measurement I_ij = m·Q/T_d² + η inside L_T, exactly 0 beyond
/// (eqs. 1, 33). No random number is drawn beyond L_T.
pub fn measure_signal<R: Rng + ?Sized>(d: f64, p: &Params, rng: &mut R) -> f64 {
    if d <= p.l_t {
        signal_noise_free(d, p) + p.noise_sigma * standard_normal(rng)
    } else {
        0.0
    }
}

/// Calibration table: nodes (I_ξ, d_ξ) with I strictly increasing (so d
/// strictly decreasing), as eq. (6) needs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Averaged signal of each node, strictly increasing.
    pub signals: Vec<f64>,
    /// Distance of each node, strictly decreasing.
    pub distances: Vec<f64>,
}

impl Calibration {
    /// Offline calibration (paper §3.2): ς distances evenly spaced in
    /// [d_min, L_T], each measured `repeats` times with eq. (33) and averaged.
    /// Distances are measured in increasing order, repeats innermost.
    pub fn build<R: Rng + ?Sized>(p: &Params, rng: &mut R) -> Self {
        assert!(p.n_distances >= 2 && p.repeats >= 1);
        let step = (p.l_t - p.d_min) / (p.n_distances - 1) as f64;
        let mut d = Vec::with_capacity(p.n_distances);
        let mut s = Vec::with_capacity(p.n_distances);
        for k in 0..p.n_distances {
            let dk = p.d_min + step * k as f64;
            let sum: f64 = (0..p.repeats).map(|_| measure_signal(dk, p, rng)).sum();
            d.push(dk);
            s.push(sum / p.repeats as f64);
        }
        Self::from_measurements(&d, &s)
    }

    /// Builds the table from averaged measurements at increasing distances.
    /// Monotonicity (signal strictly decreasing with distance) is enforced by
    /// pool-adjacent-violators isotonic regression: violating neighbours are
    /// merged into one node at their mean distance and mean signal.
    /// [chosen] spec §5 item 16 ("enforce monotonicity").
    pub fn from_measurements(distances: &[f64], signals: &[f64]) -> Self {
        assert_eq!(distances.len(), signals.len());
        assert!(
            distances.windows(2).all(|w| w[0] < w[1]),
            "distances must increase"
        );
        // blocks: (sum_d, sum_i, count), signal must strictly decrease.
        let mut blocks: Vec<(f64, f64, f64)> = Vec::new();
        for (&d, &i) in distances.iter().zip(signals) {
            blocks.push((d, i, 1.0));
            while blocks.len() >= 2 {
                let b = blocks[blocks.len() - 1];
                let a = blocks[blocks.len() - 2];
                if b.1 / b.2 >= a.1 / a.2 {
                    blocks.pop();
                    let last = blocks.last_mut().unwrap();
                    *last = (a.0 + b.0, a.1 + b.1, a.2 + b.2);
                } else {
                    break;
                }
            }
        }
        // reverse: increasing signal order for eq. (6)
        let signals = blocks.iter().rev().map(|b| b.1 / b.2).collect();
        let distances = blocks.iter().rev().map(|b| b.0 / b.2).collect();
        Self { signals, distances }
    }

    /// T_d ≈ G⁻¹(I_ij), eq. (6) with the erratum fixed (second denominator
    /// I_{ξ+1} − I_ξ, spec §6 item 1):
    ///   T_d = d_ξ (I_{ξ+1} − I)/(I_{ξ+1} − I_ξ) + d_{ξ+1} (I − I_ξ)/(I_{ξ+1} − I_ξ)
    /// for I_ξ ≤ I < I_{ξ+1}. Signals at or above the strongest node give its
    /// (nearest) distance; signals at or below the weakest node, including
    /// I ≤ 0, give the farthest node's distance (≈ L_T). [chosen] spec §5
    /// item 16.
    pub fn inverse(&self, signal: f64) -> f64 {
        let (s, d) = (&self.signals, &self.distances);
        let n = s.len();
        if n == 1 || signal.is_nan() || signal <= s[0] {
            return d[0];
        }
        if signal >= s[n - 1] {
            return d[n - 1];
        }
        // ξ: last node with I_ξ ≤ signal
        let xi = s.partition_point(|&v| v <= signal) - 1;
        let (i0, i1) = (s[xi], s[xi + 1]);
        let den = i1 - i0;
        d[xi] * (i1 - signal) / den + d[xi + 1] * (signal - i0) / den // eq. (6)
    }

    /// Calibrated forward map d → I (piecewise linear through the nodes,
    /// clamped at the end nodes). Useful to check the table.
    pub fn forward(&self, d: f64) -> f64 {
        let (s, dist) = (&self.signals, &self.distances);
        let n = s.len();
        if n == 1 || d >= dist[0] {
            return s[0];
        }
        if d <= dist[n - 1] {
            return s[n - 1];
        }
        // distances decrease: k = last node with dist >= d
        let k = dist.partition_point(|&v| v >= d) - 1;
        let t = (dist[k] - d) / (dist[k] - dist[k + 1]);
        s[k] + t * (s[k + 1] - s[k])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Linear-interpolation error bound in d: between nodes h apart at
    /// distance ≥ d, d(I) = sqrt(mQ/I) interpolated linearly in I errs by at
    /// most ≈ (3/8)·h²/d (max 0.235 for the [1,2] interval); 0.5·h²/d covers it.
    fn interp_tol(d: f64, h: f64) -> f64 {
        0.5 * h * h / d.floor().max(1.0)
    }

    #[test]
    fn signal_model_scale() {
        let p = Params::default();
        assert_eq!(signal_noise_free(10.0, &p), 100.0);
        assert_eq!(signal_noise_free(100.0, &p), 1.0);
        assert_eq!(signal_noise_free(100.5, &p), 0.0);
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        assert_eq!(measure_signal(150.0, &p, &mut rng), 0.0);
        let n = 20000;
        let xs: Vec<f64> = (0..n)
            .map(|_| measure_signal(50.0, &p, &mut rng) - 4.0)
            .collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.03, "noise mean {mean}");
        assert!((var - 1.0).abs() < 0.05, "noise variance {var}");
    }

    #[test]
    fn noise_free_calibration_inverts_exactly_up_to_interpolation() {
        let p = Params {
            noise_sigma: 0.0,
            ..Params::default()
        };
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let cal = Calibration::build(&p, &mut rng);
        assert_eq!(cal.signals.len(), 100);
        let mut d: f64 = 1.0;
        while d <= 100.0 {
            let got = cal.inverse(signal_noise_free(d, &p));
            assert!((got - d).abs() <= interp_tol(d, 1.0), "d={d} got {got}");
            d += 0.37;
        }
    }

    #[test]
    fn noisy_calibration_inverse_recovers_distance() {
        // Node averages carry noise σ/√100 = 0.1 in I; |dd/dI| = d³/(2mQ), so
        // a 4σ node error moves the estimate by 0.4·d³/(2mQ). Tolerance =
        // that + the interpolation bound. (d=10: 0.02+0.05; d=50: 2.5+0.01.)
        let p = Params::default();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let cal = Calibration::build(&p, &mut rng);
        assert!(cal.signals.windows(2).all(|w| w[0] < w[1]));
        assert!(cal.distances.windows(2).all(|w| w[0] > w[1]));
        let mut d: f64 = 1.0;
        while d <= 90.0 {
            let tol = 4.0 * 0.1 * d.powi(3) / (2.0 * p.m * p.q) + interp_tol(d, 1.0);
            let got = cal.inverse(signal_noise_free(d, &p));
            assert!((got - d).abs() <= tol, "d={d} got {got} tol {tol}");
            d += 0.5;
        }
    }

    #[test]
    fn eq6_as_printed_is_wrong() {
        // The printed second denominator (I_{ξ+1} − I) is not interpolation:
        // it misses badly where the fixed formula is near-exact (spec §6 item 1).
        let p = Params {
            noise_sigma: 0.0,
            ..Params::default()
        };
        let cal = Calibration::build(&p, &mut ChaCha8Rng::seed_from_u64(2));
        let (s, d) = (&cal.signals, &cal.distances);
        let i = signal_noise_free(30.3, &p);
        let xi = s.partition_point(|&v| v <= i) - 1;
        let printed = d[xi] * (s[xi + 1] - i) / (s[xi + 1] - s[xi])
            + d[xi + 1] * (i - s[xi]) / (s[xi + 1] - i);
        assert!((cal.inverse(i) - 30.3).abs() < interp_tol(30.3, 1.0));
        assert!(
            (printed - 30.3).abs() > 5.0,
            "printed eq. (6) gave {printed}"
        );
    }

    #[test]
    fn inverse_is_monotone_and_clamped() {
        let p = Params::default();
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let cal = Calibration::build(&p, &mut rng);
        assert!((cal.inverse(1e9) - 1.0).abs() < 1e-12);
        let far = cal.inverse(-3.0);
        assert!(far > 95.0 && far <= 100.0);
        assert_eq!(cal.inverse(0.0), far);
        let mut prev = f64::INFINITY;
        let mut i = 0.0;
        while i < 12000.0 {
            let d = cal.inverse(i);
            assert!(d <= prev + 1e-12, "not monotone at I={i}");
            prev = d;
            i += 0.25;
        }
        // forward and inverse agree on the nodes' span
        for d in [2.0, 7.5, 33.0, 61.0] {
            assert!((cal.inverse(cal.forward(d)) - d).abs() < 1e-9);
        }
    }

    #[test]
    fn pava_merges_violations() {
        // signals at increasing distances with one violation (3 then 3.4)
        let cal = Calibration::from_measurements(&[1.0, 2.0, 3.0, 4.0], &[10.0, 3.0, 3.4, 1.0]);
        assert_eq!(cal.signals, vec![1.0, 3.2, 10.0]);
        assert_eq!(cal.distances, vec![4.0, 2.5, 1.0]);
    }

    #[test]
    fn deterministic_given_seed() {
        let p = Params::default();
        let a = Calibration::build(&p, &mut ChaCha8Rng::seed_from_u64(9));
        let b = Calibration::build(&p, &mut ChaCha8Rng::seed_from_u64(9));
        assert_eq!(a, b);
    }
}
