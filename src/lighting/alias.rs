//! pbrt-v4's alias table (`AliasTable`, util/sampling.h), built in f64:
//! Vose's method, which picks entry i with probability wᵢ/Σw in O(1) from
//! one random number. Each bin i keeps i with probability q, else gives its
//! alias; `sample_emitter` reads the bins (shaders/lights.wgsl).

/// One bin: pbrt's `Bin` (its `p` is the entry's probability).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bin {
    pub p: f64,
    pub q: f64,
    pub alias: u32,
}

/// The bins of `weights` (each finite and > 0, at least one), as pbrt-v4
/// builds them: bins under 1 (p·n < 1) are filled from bins over it, the
/// excess passed on; bins left over, by rounding, keep themselves (q = 1).
pub fn alias_table(weights: &[f64]) -> Vec<Bin> {
    let sum: f64 = weights.iter().sum();
    let n = weights.len() as f64;
    let mut bins: Vec<Bin> = weights
        .iter()
        .enumerate()
        .map(|(i, &w)| Bin {
            p: w / sum,
            q: 1.0,
            alias: i as u32,
        })
        .collect();
    // Each bin's index and its probability times n (pbrt's p̂).
    type Scaled = Vec<(usize, f64)>;
    let (mut under, mut over): (Scaled, Scaled) = bins
        .iter()
        .enumerate()
        .map(|(i, b)| (i, b.p * n))
        .partition(|&(_, p_hat)| p_hat < 1.0);
    while let (Some(&(u, u_hat)), Some(&(o, o_hat))) = (under.last(), over.last()) {
        under.pop();
        over.pop();
        bins[u].q = u_hat;
        bins[u].alias = o as u32;
        let excess = u_hat + o_hat - 1.0;
        if excess < 1.0 {
            under.push((o, excess));
        } else {
            over.push((o, excess));
        }
    }
    bins
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each entry's probability, summed over the bins that give it, is its
    /// weight's share.
    #[test]
    fn the_bins_give_each_entry_its_share() {
        let weights = [1.0, 7.0, 0.5, 2.5, 3.0];
        let bins = alias_table(&weights);
        let n = bins.len() as f64;
        let mut given = [0.0; 5];
        for (i, bin) in bins.iter().enumerate() {
            given[i] += bin.q / n;
            given[bin.alias as usize] += (1.0 - bin.q) / n;
        }
        let sum: f64 = weights.iter().sum();
        for (g, w) in given.iter().zip(weights) {
            assert!((g - w / sum).abs() < 1e-12, "{given:?}");
        }
    }
}
