//! Images: the tables images need ([`Sky::prepare_images`]) and the
//! renders ([`Sky::render_xyz`], [`Sky::render_stokes_xyz`],
//! [`Sky::render_spectral`]), each pixel composed as a view is, the sun's
//! disc drawn energy-true (`sky/sun_disc.rs`).

use super::options::{
    ImageSettings, MAX_IMAGE_BUFFER_BYTES, Method, Polarisation, check_image_size,
};
use super::setup::Sky;
use super::{k_terms, sun_disc};

use crate::colour::{SpectrumToXyz, Xyz};
use crate::error::{Error, Result};
use crate::transport::multiple_scattering::MultipleScatteringTable;
use std::sync::Arc;

impl Sky {
    /// Builds everything images of this sky need (the multiple-scattering
    /// field and its source table; for the fast method the sun-column and
    /// sky-view tables), so that a progress display can show it as its
    /// own phase; rendering does it on first use otherwise.
    pub fn prepare_images(&self) -> Result<()> {
        if !self.k_terms.is_empty() {
            return self.prepare_term_tables(false);
        }
        self.prepare_field_for_images()?;
        self.source_table();
        if self.method == Method::Fast {
            self.image_tables();
        }
        Ok(())
    }

    /// The fast method's tables of the k-distribution's term skies, for
    /// images (`Sky::image_tables`) or, `for_views`, for many views
    /// (`Sky::view_tables`): each term's field and source table, then the
    /// tables of the terms that have none yet, together
    /// (`Sky::compute_tables_together`: the terms' view rays are the
    /// same, so each march node's columns toward the sun are looked up
    /// once), bit for bit each term's own.
    pub(super) fn prepare_term_tables(&self, for_views: bool) -> Result<()> {
        let mut together: Vec<&Sky> = Vec::new();
        for (_, term) in &self.k_terms {
            term.prepare_field_for_images()?;
            if !for_views {
                term.source_table();
            }
            let slot = if for_views {
                &term.view_tables
            } else {
                &term.image_tables
            };
            let same_sizes = together.first().is_none_or(|first| {
                (first.table_size, first.multiple_stride, first.sky_view_rows)
                    == (term.table_size, term.multiple_stride, term.sky_view_rows)
            });
            if term.method == Method::Fast && slot.get().is_none() && same_sizes {
                together.push(term);
            } else if for_views {
                term.view_tables();
            } else {
                term.prepare_images()?;
            }
        }
        // The views' tables march through a source table at half the
        // steps (`Sky::view_tables`), made for them alone.
        let half_steps: Vec<_> = together
            .iter()
            .map(|term| {
                term.field
                    .get()
                    .filter(|_| for_views)
                    .map(|field| MultipleScatteringTable::compute_at_half_steps(Arc::clone(field)))
            })
            .collect();
        let skies: Vec<_> = together
            .iter()
            .zip(&half_steps)
            .map(|(term, half_steps)| {
                let source = if for_views {
                    half_steps.as_ref()
                } else {
                    term.source_table()
                };
                (*term, source)
            })
            .collect();
        for (term, tables) in together
            .iter()
            .zip(Sky::compute_tables_together(&skies, true))
        {
            let slot = if for_views {
                &term.view_tables
            } else {
                &term.image_tables
            };
            // Another thread may have been first: the tables are the same.
            let _ = slot.set(tables);
        }
        Ok(())
    }

    /// `to_xyz` must be on the sky's grid, and the grid must have a
    /// wavelength in 360-830 nm (colour comes from those; see
    /// [`SpectrumToXyz`]).
    pub(super) fn check_colour_conversion(&self, to_xyz: &SpectrumToXyz) -> Result<()> {
        if to_xyz.grid() != self.wavelengths() {
            return Err(Error::InvalidSpectrum(
                "the colour conversion and the sky use different wavelength grids".into(),
            ));
        }
        if to_xyz.colour_sample_count() == 0 {
            return Err(Error::Unsupported(format!(
                "no wavelength of the grid {} lies in {}-{} nm, the range of the colour-matching functions, so it gives no colour: use a grid that overlaps that range (a spectral image takes any grid)",
                self.wavelengths(),
                crate::colour::CIE_MIN_WAVELENGTH_NM,
                crate::colour::CIE_MAX_WAVELENGTH_NM
            )));
        }
        Ok(())
    }

    /// The image `image` as CIE XYZ per pixel (row-major, top row first;
    /// black where the camera sees nothing), converted by `to_xyz` (which
    /// must be on the sky's grid; colour comes from the grid's wavelengths
    /// in 360-830 nm, and a grid with none there is an error);
    /// `progress(rows)` is called as rows complete (from worker threads).
    pub fn render_xyz(
        &self,
        image: &ImageSettings,
        to_xyz: &SpectrumToXyz,
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<Vec<Xyz>> {
        self.check_colour_conversion(to_xyz)?;
        if !self.k_terms.is_empty() {
            self.check_image::<Xyz>(image, 1)?;
            self.prepare_images()?;
            let (skies, conversions) = self.term_colour_conversions(to_xyz);
            return Sky::render_pixels_of(
                &skies,
                image,
                (1, Xyz::BLACK),
                progress,
                |k, radiance, pixel| {
                    let (weight, to_xyz) = &conversions[k];
                    let n = skies[k].wavelengths().len();
                    let xyz = to_xyz.to_xyz_unchecked(&radiance[..n]);
                    k_terms::add_scaled_xyz(&mut pixel[0], *weight, &xyz);
                },
            );
        }
        let n = self.wavelengths().len();
        self.render_pixels(image, 1, Xyz::BLACK, progress, |radiance, pixel| {
            pixel[0] = to_xyz.to_xyz_unchecked(&radiance[..n])
        })
    }

    /// The image `image` of a polarised sky ([`Polarisation::Vector`]) as
    /// the CIE XYZ of its Stokes vector per pixel: [S0, S1, S2, S3] = the
    /// XYZ of the spectra I, Q, U and V (XYZ is linear in the spectrum, so
    /// Q, U and V map as I does and may be negative), Q and U referred to
    /// each pixel's meridian plane (the convention of [`Stokes`](super::Stokes)); the
    /// sun's disc, unpolarised, adds to S0 only. Row-major, top row first,
    /// black where the camera sees nothing. An error for a scalar sky.
    pub fn render_stokes_xyz(
        &self,
        image: &ImageSettings,
        to_xyz: &SpectrumToXyz,
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<Vec<[Xyz; 4]>> {
        if self.polarisation != Polarisation::Vector {
            return Err(Error::Unsupported(
                "Stokes images: the sky is scalar; build it with Polarisation::Vector".into(),
            ));
        }
        self.check_colour_conversion(to_xyz)?;
        let stokes_xyz = |to_xyz: &SpectrumToXyz, stokes: &[f64], n: usize| {
            [
                to_xyz.to_xyz_unchecked(&stokes[..n]),
                to_xyz.weighted_sum(&stokes[n..2 * n]),
                to_xyz.weighted_sum(&stokes[2 * n..3 * n]),
                to_xyz.weighted_sum(&stokes[3 * n..]),
            ]
        };
        if !self.k_terms.is_empty() {
            self.check_image::<[Xyz; 4]>(image, 1)?;
            self.prepare_images()?;
            let (skies, conversions) = self.term_colour_conversions(to_xyz);
            return Sky::render_pixels_of(
                &skies,
                image,
                (1, [Xyz::BLACK; 4]),
                progress,
                |k, stokes, pixel| {
                    let (weight, to_xyz) = &conversions[k];
                    let xyz = stokes_xyz(to_xyz, stokes, skies[k].wavelengths().len());
                    for (s, x) in pixel[0].iter_mut().zip(&xyz) {
                        k_terms::add_scaled_xyz(s, *weight, x);
                    }
                },
            );
        }
        let n = self.wavelengths().len();
        self.render_pixels(image, 1, [Xyz::BLACK; 4], progress, |stokes, pixel| {
            pixel[0] = stokes_xyz(to_xyz, stokes, n)
        })
    }

    /// The image `image` as spectral radiance, W m^-2 sr^-1 nm^-1:
    /// `width * height * wavelengths` values, pixel-major (row-major
    /// pixels, top row first, each pixel's wavelengths together).
    pub fn render_spectral(
        &self,
        image: &ImageSettings,
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<Vec<f64>> {
        if self.colour_only {
            return Err(Error::Unsupported(
                "spectral images: this sky was built for colour images alone (SkyBuilder::for_colour_images folds its gas terms where colour allows); build it without that".into(),
            ));
        }
        if !self.k_terms.is_empty() {
            let n = self.wavelengths().len();
            self.check_image::<f64>(image, n)?;
            self.prepare_images()?;
            let add = |sum: &mut f64, w: f64, x: &f64| *sum += w * x;
            return self.sum_term_images(progress, 0.0, add, |(offset, weights), term, p| {
                let values = term.render_spectral(image, p)?;
                let uniform = k_terms::uniform_weight(weights);
                if uniform.is_some() && weights.len() == n {
                    return Ok(uniform.map(|weight| (weight, values)));
                }
                // Pixel-major: each pixel's wavelengths together, weighted
                // and placed on this sky's grid.
                let mut on_grid = vec![0.0; values.len() / weights.len() * n];
                for (pixel, out) in values.chunks(weights.len()).zip(on_grid.chunks_mut(n)) {
                    for ((o, v), w) in out[offset..].iter_mut().zip(pixel).zip(weights.values()) {
                        *o = v * w;
                    }
                }
                Ok(Some((1.0, on_grid)))
            });
        }
        let wavelengths = self.wavelengths().len();
        self.render_pixels(image, wavelengths, 0.0, progress, |radiance, pixel| {
            pixel.copy_from_slice(&radiance[..wavelengths])
        })
    }

    /// An error for an image this sky cannot render: too many pixels, a
    /// buffer of `per_pixel` values of type T per pixel over the limit,
    /// or the path-tracing method (it computes views).
    fn check_image<T>(&self, image: &ImageSettings, per_pixel: usize) -> Result<()> {
        let (width, height) = (image.width, image.height);
        check_image_size(width, height)?;
        let buffer_bytes = u64::from(width)
            * u64::from(height)
            * per_pixel as u64
            * std::mem::size_of::<T>() as u64;
        if buffer_bytes > MAX_IMAGE_BUFFER_BYTES {
            return Err(Error::out_of_range(
                format!(
                    "image buffer ({width} x {height} pixels x {per_pixel} values of {} bytes)",
                    std::mem::size_of::<T>()
                ),
                buffer_bytes as f64 / f64::from(1u32 << 30),
                "GiB",
                format!(
                    "<= {}: render fewer pixels (or fewer wavelengths for a spectral image)",
                    MAX_IMAGE_BUFFER_BYTES >> 30
                ),
            ));
        }
        if let Method::PathTracing { .. } = self.method {
            return Err(Error::Unsupported(
                "path tracing computes views, not images: render with the fast or reference method"
                    .into(),
            ));
        }
        Ok(())
    }

    /// Renders every pixel's radiance and stores it through `store` into
    /// `per_pixel` values of type T: `store` gets the pixel's spectral
    /// radiance (the polarised intensity I of a polarised sky), followed
    /// for a polarised sky by its Q, U and V.
    fn render_pixels<T: Copy + Send>(
        &self,
        image: &ImageSettings,
        per_pixel: usize,
        black: T,
        progress: &(dyn Fn(usize) + Sync),
        store: impl Fn(&[f64], &mut [T]) + Sync,
    ) -> Result<Vec<T>> {
        Sky::render_pixels_of(
            &[self],
            image,
            (per_pixel, black),
            progress,
            |_, spectra, pixel| store(spectra, pixel),
        )
    }

    /// [`Sky::render_pixels`] of several skies in one pass (the
    /// k-distribution's terms: `sky/k_terms.rs`): each pixel's direction
    /// found once, then each sky's spectra in turn stored through
    /// `store(k, spectra of skies[k], pixel)` (the pixel starts `black`;
    /// a store that adds w_k times the sky's colour sums the terms in the
    /// order and with the operations of [`k_terms::weighted_images`], bit
    /// for bit, without an image per term).
    fn render_pixels_of<T: Copy + Send>(
        skies: &[&Sky],
        image: &ImageSettings,
        (per_pixel, black): (usize, T),
        progress: &(dyn Fn(usize) + Sync),
        store: impl Fn(usize, &[f64], &mut [T]) + Sync,
    ) -> Result<Vec<T>> {
        let (width, height) = (image.width, image.height);
        // What each sky reads: its tables (built first, outside the
        // parallel loop, see `prepare_field`), its direct beam and its
        // sun's disc (its share of each pixel it touches, per sr).
        struct Reads<'a> {
            sky: &'a Sky,
            source_table: Option<&'a MultipleScatteringTable>,
            tables: Option<&'a super::setup::ImageTables>,
            direct_normal: crate::spectrum::SampledSpectrum,
            disc: Vec<(usize, f64)>,
        }
        let mut reads = Vec::with_capacity(skies.len());
        for sky in skies {
            sky.check_image::<T>(image, per_pixel)?;
            sky.prepare_field_for_images()?;
            let disc = if image.draw_sun_disc {
                sun_disc::compute_disc_pixels(
                    &image.camera,
                    width,
                    height,
                    sky.sun_direction(),
                    sky.scene.sun_angular_radius_rad(),
                    |direction| sky.scene.sees_sky(direction),
                )
            } else {
                Vec::new()
            };
            reads.push(Reads {
                sky,
                source_table: sky.source_table(),
                tables: (sky.method == Method::Fast).then(|| sky.image_tables()),
                direct_normal: sky.direct_normal_irradiance(),
                disc,
            });
        }
        // Per sky: whether it reads the first's pixel geometry (the terms'
        // skies: the same sun and table axes), bit for bit its own.
        let shares_geometry: Vec<bool> = reads
            .iter()
            .map(|r| match (reads[0].tables, r.tables) {
                (Some(first), Some(tables)) => {
                    reads[0].sky.has_pixel_geometry_of(first, (r.sky, tables))
                }
                _ => false,
            })
            .collect();
        let rows_done = std::sync::atomic::AtomicUsize::new(0);
        let row_length = width as usize * per_pixel;
        let mut pixels = vec![black; row_length * height as usize];
        crate::parallel::for_each_chunk_mut(&mut pixels, row_length, |row, values| {
            let mut works: Vec<_> = reads
                .iter()
                .map(|r| {
                    let wavelengths = r.sky.wavelengths().len();
                    let components = if r.sky.polarisation == Polarisation::Vector {
                        4
                    } else {
                        1
                    };
                    (r.sky.view_work(), vec![0.0; components * wavelengths])
                })
                .collect();
            for (column, pixel) in values.chunks_mut(per_pixel).enumerate() {
                let Some(view) =
                    image
                        .camera
                        .direction_for_pixel(column as u32, row as u32, width, height)
                else {
                    continue;
                };
                let index = row * width as usize + column;
                let mut first_geometry = None;
                for (k, (r, (work, spectra))) in reads.iter().zip(works.iter_mut()).enumerate() {
                    let sky = r.sky;
                    let (radiance, stokes) = spectra.split_at_mut(sky.wavelengths().len());
                    // A polarised sky has the fast method's tables (the
                    // reference march is scalar: `Sky::set_polarisation`).
                    match r.tables {
                        Some(tables) => {
                            let pixel = match first_geometry {
                                Some(pixel) if shares_geometry[k] => pixel,
                                _ => sky.pixel_geometry(view, tables),
                            };
                            if k == 0 {
                                first_geometry = Some(pixel);
                            }
                            sky.compute_pixel_radiance(&pixel, tables, work, radiance);
                            if sky.polarisation == Polarisation::Vector {
                                sky.add_pixel_stokes(&pixel, tables, work, radiance, stokes);
                            }
                        }
                        None => sky.compute_view_radiance(view, r.source_table, work, radiance),
                    }
                    if let Ok(d) = r.disc.binary_search_by_key(&index, |(pixel, _)| *pixel) {
                        let per_sr = r.disc[d].1;
                        for (v, e) in radiance.iter_mut().zip(r.direct_normal.values()) {
                            *v += e * per_sr;
                        }
                    }
                    store(k, spectra, pixel);
                }
            }
            progress(rows_done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
        });
        Ok(pixels)
    }
}
