//! Deterministic random numbers for Monte Carlo transport.
//!
//! A Monte Carlo result must not depend on how the work was spread over
//! threads, so every sample (one light path) draws from its own stream,
//! addressed by `(seed, sample index)`, never from a generator shared
//! between samples. [`RandomStream`] is the SplitMix64 generator of
//! Steele, Lea & Flood ("Fast splittable pseudorandom number generators",
//! OOPSLA 2014; Java's `SplittableRandom`): a Weyl sequence
//! `state_k = state_0 + k * gamma (mod 2^64)` passed through a strong
//! 64-bit finaliser (Stafford's "Mix13"). It passes BigCrush, costs a few
//! nanoseconds a number, and is counter-based in effect: the k-th number of
//! a stream depends only on (state_0, gamma, k).
//!
//! Streams: `state_0` and `gamma` are both hashes of (seed, sample index),
//! so two samples' streams are different sequences rather than shifted
//! copies of one sequence (with a shared gamma, two streams would overlap
//! whenever their starting points fell within a path's number of draws of
//! each other). `gamma` is forced odd (a full period of 2^64) and, as in
//! `SplittableRandom::mixGamma`, away from the weak gammas with few bit
//! transitions.

/// The golden-ratio increment of SplitMix64, 2^64 / phi, odd.
const GOLDEN_GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// Stafford's Mix13 finaliser (a bijection of u64 with full avalanche).
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Stafford's Mix04 variant used by `SplittableRandom` for gammas: odd,
/// with at least 24 bit transitions.
fn mix_gamma(mut z: u64) -> u64 {
    z = (z ^ (z >> 33)).wrapping_mul(0xFF51_AFD7_ED55_8CCD);
    z = (z ^ (z >> 33)).wrapping_mul(0xC4CE_B9FE_1A85_EC53);
    z = (z ^ (z >> 33)) | 1;
    if (z ^ (z >> 1)).count_ones() < 24 {
        z ^ 0xAAAA_AAAA_AAAA_AAAA
    } else {
        z
    }
}

/// One stream of uniform random numbers (see the module docs).
#[derive(Debug, Clone)]
pub struct RandomStream {
    state: u64,
    gamma: u64,
}

impl RandomStream {
    /// The stream of sample `stream_index` for the run seeded `seed`.
    /// Different (seed, index) pairs give unrelated streams.
    pub(crate) fn new(seed: u64, stream_index: u64) -> RandomStream {
        // Two rounds of the bijective mixer: seed and index are combined
        // after the seed is mixed, so (s, i) and (i, s) differ.
        let key = mix64(mix64(seed ^ 0x5851_F42D_4C95_7F2D).wrapping_add(stream_index));
        RandomStream {
            state: mix64(key.wrapping_add(GOLDEN_GAMMA)),
            gamma: mix_gamma(key.wrapping_add(GOLDEN_GAMMA.wrapping_mul(2))),
        }
    }

    /// The next 64 random bits.
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(self.gamma);
        mix64(self.state)
    }

    /// A uniform number in [0, 1) with 53 random bits (every double of the
    /// form k / 2^53).
    pub(crate) fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// A uniform index in 0..n (n > 0), by Lemire's multiply-shift (the
    /// bias, below n / 2^64, is far under any Monte Carlo error).
    pub(crate) fn next_index(&mut self, n: usize) -> usize {
        debug_assert!(n > 0);
        ((self.next_u64() as u128 * n as u128) >> 64) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_reproducible_and_distinct() {
        let mut a = RandomStream::new(1, 7);
        let mut b = RandomStream::new(1, 7);
        let first: Vec<u64> = (0..8).map(|_| a.next_u64()).collect();
        let again: Vec<u64> = (0..8).map(|_| b.next_u64()).collect();
        assert_eq!(first, again);
        let mut c = RandomStream::new(1, 8);
        let mut d = RandomStream::new(2, 7);
        let mut e = RandomStream::new(7, 1);
        for other in [&mut c, &mut d, &mut e] {
            let values: Vec<u64> = (0..8).map(|_| other.next_u64()).collect();
            assert!(values.iter().all(|v| !first.contains(v)));
        }
    }

    /// Mean, variance and lag-1 correlation of the uniforms, pooled over
    /// many short streams (as the path tracer uses them), within 5 sigma.
    #[test]
    fn uniforms_have_the_moments_of_u01() {
        let (streams, per_stream) = (20_000u64, 50);
        let n = (streams * per_stream) as f64;
        let (mut sum, mut sum_squares, mut lag) = (0.0, 0.0, 0.0);
        for s in 0..streams {
            let mut random = RandomStream::new(42, s);
            let mut previous = random.next_f64();
            sum += previous;
            sum_squares += previous * previous;
            for _ in 1..per_stream {
                let u = random.next_f64();
                assert!((0.0..1.0).contains(&u));
                sum += u;
                sum_squares += u * u;
                lag += (u - 0.5) * (previous - 0.5);
                previous = u;
            }
        }
        let mean = sum / n;
        let variance = sum_squares / n - mean * mean;
        // sd of the mean of U(0,1): sqrt(1/12 / n); of the sample variance:
        // sqrt((1/80 - 1/144) / n); of the lag product: 1/12 / sqrt(n).
        assert!((mean - 0.5).abs() < 5.0 * (1.0 / 12.0 / n).sqrt(), "{mean}");
        assert!(
            (variance - 1.0 / 12.0).abs() < 5.0 * ((1.0 / 80.0 - 1.0 / 144.0) / n).sqrt(),
            "{variance}"
        );
        let lag_mean = lag / (n - streams as f64);
        assert!(lag_mean.abs() < 5.0 / 12.0 / n.sqrt(), "{lag_mean}");
        // The first numbers of neighbouring streams are uncorrelated too.
        let mut cross = 0.0;
        for s in 0..streams {
            let u = RandomStream::new(42, s).next_f64();
            let v = RandomStream::new(42, s + 1).next_f64();
            cross += (u - 0.5) * (v - 0.5);
        }
        let cross_mean = cross / streams as f64;
        assert!(
            cross_mean.abs() < 5.0 / 12.0 / (streams as f64).sqrt(),
            "{cross_mean}"
        );
    }

    #[test]
    fn indices_are_uniform() {
        let mut random = RandomStream::new(3, 0);
        let mut counts = [0usize; 21];
        let n = 210_000;
        for _ in 0..n {
            counts[random.next_index(21)] += 1;
        }
        let expected = n as f64 / 21.0;
        for count in counts {
            assert!(
                (count as f64 - expected).abs() < 5.0 * expected.sqrt(),
                "{counts:?}"
            );
        }
    }
}
