//! What the tracer reports and how: the spectra with their standard errors
//! ([`PathTracedSpectrum`]), the parts of each sample's light, and the runs
//! of fixed-size chunks whose statistics are merged in a fixed order (the
//! module docs' "What it reports" and "Determinism").

use std::sync::atomic::{AtomicU64, Ordering};

use super::tracer::PathTracer;
use crate::error::{Error, Result};
use crate::geometry::Vector3;
use crate::spectrum::SampledSpectrum;
use crate::transport::random::RandomStream;

/// Samples per chunk of work: the unit of parallelism and of the fixed
/// summation order.
pub(crate) const SAMPLES_PER_CHUNK: u64 = 1024;

/// Chunks whose statistics are kept at once (see `PathTracer::run`): the
/// memory of a run is this many times 2 x 8 bytes per value of a sample
/// ((4 + 4 Stokes) parts x wavelengths), at most 330 MB at 10 000
/// wavelengths, whatever the number of samples.
pub(super) const CHUNKS_PER_BATCH: usize = 256;

/// The most paths one run traces (`--samples`): a bound on time (the
/// statistics are kept for one batch of chunks at a time, so memory does
/// not grow with the number of paths).
pub const MAX_SAMPLES: u64 = 1_000_000_000;

/// A spectrum estimated by Monte Carlo: the sample mean and its standard
/// error per wavelength (same unit as the mean).
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralEstimate {
    pub mean: SampledSpectrum,
    pub standard_error: SampledSpectrum,
}

/// The largest of |error / mean| over paired values (0 where the error is
/// 0, infinite where only the mean is).
pub(crate) fn worst_relative_error(mean: &[f64], error: &[f64]) -> f64 {
    mean.iter()
        .zip(error)
        .map(|(m, e)| if *e == 0.0 { 0.0 } else { e / m.abs() })
        .fold(0.0, f64::max)
}

/// What [`PathTracer`] returns: the total and its parts by the light's
/// history (see the module docs), each with its standard error. Radiance
/// in W m^-2 sr^-1 nm^-1 ([`PathTracer::compute_radiance`]) or irradiance in
/// W m^-2 nm^-1 ([`PathTracer::compute_irradiance`]).
#[derive(Debug, Clone, PartialEq)]
pub struct PathTracedSpectrum {
    /// Number of paths.
    pub samples: u64,
    /// All orders of scattering and ground reflection.
    pub total: SpectralEstimate,
    /// Exactly one scattering in the air, no ground.
    pub single_scattering: SpectralEstimate,
    /// The directly sunlit ground seen along the view, no scattering.
    pub sunlit_ground: SpectralEstimate,
    /// Everything with two or more interactions.
    pub multiple_scattering: SpectralEstimate,
    /// The Stokes vector of the total (I, Q, U, V), from a polarised
    /// tracer ([`PathTracer::new_polarised`]); its I is the polarised
    /// intensity, which differs from the scalar `total` (see the module
    /// docs of `stokes.rs` for the frame).
    pub stokes: Option<[SpectralEstimate; 4]>,
}

/// The light's history at a scoring event, an index into the per-sample
/// contributions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Part {
    SingleScattering = 0,
    SunlitGround = 1,
    MultipleScattering = 2,
}

/// Parts kept per sample: the three histories and their total.
pub(super) const PARTS: usize = 4;

pub(super) const TOTAL: usize = 3;

/// A polarised tracer keeps the Stokes vector of the total after them.
pub(super) const STOKES_PARTS: usize = 4;

/// Running mean and sum of squared deviations of every per-sample value
/// ([part * wavelengths + i]) over a chunk (Welford).
#[derive(Debug, Clone, Default)]
pub(super) struct ChunkStatistics {
    pub(super) count: u64,
    pub(super) mean: Vec<f64>,
    pub(super) squared_deviations: Vec<f64>,
}

impl ChunkStatistics {
    /// Empties the statistics, keeping their buffers.
    pub(super) fn clear(&mut self) {
        self.count = 0;
        self.mean.fill(0.0);
        self.squared_deviations.fill(0.0);
    }

    pub(super) fn add(&mut self, values: &[f64]) {
        if self.mean.is_empty() {
            self.mean = vec![0.0; values.len()];
            self.squared_deviations = vec![0.0; values.len()];
        }
        self.count += 1;
        let inverse_count = 1.0 / self.count as f64;
        for ((mean, m2), x) in self
            .mean
            .iter_mut()
            .zip(&mut self.squared_deviations)
            .zip(values)
        {
            let delta = x - *mean;
            *mean += delta * inverse_count;
            *m2 += delta * (x - *mean);
        }
    }

    /// Chan et al.'s pairwise combination of two chunks' statistics.
    pub(super) fn merge(&mut self, other: &ChunkStatistics) {
        if other.count == 0 {
            return;
        }
        if self.count == 0 {
            *self = other.clone();
            return;
        }
        let (na, nb) = (self.count as f64, other.count as f64);
        let n = na + nb;
        for i in 0..self.mean.len() {
            let delta = other.mean[i] - self.mean[i];
            self.mean[i] += delta * nb / n;
            self.squared_deviations[i] += other.squared_deviations[i] + delta * delta * na * nb / n;
        }
        self.count += other.count;
    }
}

impl<'a> PathTracer<'a> {
    /// Traces `samples` paths, the view of each from `choose_view` (a
    /// direction, its polarisation reference and a weight), in fixed chunks
    /// (see the module docs).
    pub(super) fn run(
        &self,
        samples: u64,
        seed: u64,
        progress: &(dyn Fn(u64) + Sync),
        choose_view: impl Fn(&mut RandomStream) -> (Vector3, Vector3, f64) + Sync,
    ) -> Result<PathTracedSpectrum> {
        if samples < 2 {
            return Err(Error::out_of_range(
                "samples",
                samples as f64,
                "1",
                ">= 2 (a standard error needs two samples)",
            ));
        }
        if samples > MAX_SAMPLES {
            return Err(Error::out_of_range(
                "samples",
                samples as f64,
                "1",
                "<= 1e9 (hours of computing at 30 000-70 000 paths/s; for more, average runs with different seeds)",
            ));
        }
        // Chunks run in batches of CHUNKS_PER_BATCH, each batch's
        // statistics merged in chunk order before the next starts: the same
        // sums in the same order as merging all chunks at the end, with
        // memory for one batch only.
        let chunks = samples.div_ceil(SAMPLES_PER_CHUNK) as usize;
        let mut batch = vec![ChunkStatistics::default(); chunks.min(CHUNKS_PER_BATCH)];
        let samples_done = AtomicU64::new(0);
        let mut combined = ChunkStatistics::default();
        for batch_start in (0..chunks).step_by(CHUNKS_PER_BATCH) {
            let statistics = &mut batch[..(chunks - batch_start).min(CHUNKS_PER_BATCH)];
            statistics.iter_mut().for_each(ChunkStatistics::clear);
            crate::parallel::for_each_chunk_mut(statistics, 1, |k, slot| {
                let first = (batch_start + k) as u64 * SAMPLES_PER_CHUNK;
                let last = (first + SAMPLES_PER_CHUNK).min(samples);
                let mut scratch = self.scratch();
                let statistics = &mut slot[0];
                for sample in first..last {
                    let mut random = RandomStream::new(seed, sample);
                    let (view, reference, weight) = choose_view(&mut random);
                    self.trace_path(view, reference, weight, &mut random, &mut scratch);
                    statistics.add(&scratch.contributions);
                }
                progress(samples_done.fetch_add(last - first, Ordering::Relaxed) + (last - first));
            });
            for chunk in statistics.iter() {
                combined.merge(chunk);
            }
        }
        let n = self.wavelengths;
        let count = combined.count as f64;
        let estimate = |part: usize| SpectralEstimate {
            mean: SampledSpectrum::from_values(combined.mean[part * n..(part + 1) * n].to_vec()),
            standard_error: SampledSpectrum::from_values(
                combined.squared_deviations[part * n..(part + 1) * n]
                    .iter()
                    .map(|m2| (m2.max(0.0) / (count - 1.0) / count).sqrt())
                    .collect(),
            ),
        };
        Ok(PathTracedSpectrum {
            samples,
            total: estimate(TOTAL),
            single_scattering: estimate(Part::SingleScattering as usize),
            sunlit_ground: estimate(Part::SunlitGround as usize),
            multiple_scattering: estimate(Part::MultipleScattering as usize),
            stokes: self.polarised.then(|| {
                [
                    estimate(PARTS),
                    estimate(PARTS + 1),
                    estimate(PARTS + 2),
                    estimate(PARTS + 3),
                ]
            }),
        })
    }
}
