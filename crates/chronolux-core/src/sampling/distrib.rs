//! Discrete distributions (piecewise-constant 1D over items).

/// A discrete distribution over `n` items proportional to non-negative weights.
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    /// cdf[i] = sum of normalised weights before i; cdf[n] = 1.
    cdf: Vec<f32>,
    pmf: Vec<f32>,
    total: f32,
}

impl Distribution1D {
    /// `None` when the weights are empty, negative, non-finite or sum to zero.
    pub fn new(weights: &[f32]) -> Option<Self> {
        if weights.iter().any(|w| !(w.is_finite() && *w >= 0.0)) {
            return None;
        }
        let total: f64 = weights.iter().map(|&w| w as f64).sum();
        if !(total > 0.0) {
            return None;
        }
        let mut cdf = Vec::with_capacity(weights.len() + 1);
        let mut acc = 0.0f64;
        cdf.push(0.0);
        for &w in weights {
            acc += w as f64;
            cdf.push((acc / total) as f32);
        }
        *cdf.last_mut().unwrap() = 1.0;
        let pmf = weights.iter().map(|&w| (w as f64 / total) as f32).collect();
        Some(Distribution1D {
            cdf,
            pmf,
            total: total as f32,
        })
    }

    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// Sum of the weights.
    pub fn total(&self) -> f32 {
        self.total
    }

    /// Probability of item `i`.
    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf[i]
    }

    /// Samples an item; returns (index, probability, `u` remapped to [0,1) within the item).
    pub fn sample(&self, u: f32) -> (usize, f32, f32) {
        let n = self.pmf.len();
        // First cdf entry > u, minus one, skipping zero-probability items.
        let mut i = self
            .cdf
            .partition_point(|&c| c <= u)
            .saturating_sub(1)
            .min(n - 1);
        while self.pmf[i] == 0.0 && i + 1 < n {
            i += 1;
        }
        while self.pmf[i] == 0.0 && i > 0 {
            i -= 1;
        }
        let p = self.pmf[i];
        let du = ((u - self.cdf[i]) / p).clamp(0.0, super::rng::ONE_MINUS_EPSILON);
        (i, p, du)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampling_frequencies_match_weights() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]).unwrap();
        let mut counts = [0u32; 3];
        let n = 40_000;
        for k in 0..n {
            let (i, p, u) = d.sample((k as f32 + 0.5) / n as f32);
            assert!((0.0..1.0).contains(&u));
            assert_eq!(p, d.pmf(i));
            counts[i] += 1;
        }
        assert_eq!(counts[1], 0);
        // Stratified inputs: frequencies exact to within one stratum per boundary.
        assert!((counts[0] as i64 - 10_000).abs() <= 1);
        assert!(Distribution1D::new(&[0.0]).is_none());
        assert!(Distribution1D::new(&[f32::NAN]).is_none());
    }
}
