//! Sampling, the twin of shaders/sample.wgsl: camera rays (through the
//! camera's basis, `camera::f32`/`f64::CameraBasis`), stratified hashed
//! sample positions, and a pixel's samples and mean. Written once for both
//! precisions: `kernel!` (kernel.rs) expands it into `cpu::f32` and
//! `cpu::f64`, whose `Real`, `Vec3` and `Vec4` it takes.

/// The stage's items, expanded into the module that invokes it (`kernel!`).
macro_rules! sample {
    () => {
        impl<'a> Kernel<'a> {
            /// Pinhole camera; `pixel` in pixel units, row 0 at the top.
            pub fn camera_ray(&self, pixel_x: Real, pixel_y: Real) -> Ray {
                let c = &self.camera;
                let sx = (2.0 * pixel_x / c.width as Real - 1.0) * c.tan_half_x;
                let sy = (1.0 - 2.0 * pixel_y / c.height as Real) * c.tan_half_y;
                let dir = (c.forward + sx * c.right + sy * c.up).normalize();
                Ray {
                    origin: c.eye,
                    tmin: 0.0,
                    dir,
                    tmax: FAR,
                }
            }

            /// Position of sample `sample` in pixel (x, y): the centre when spp = 1,
            /// else a jittered point in its cell of the stratified grid.
            pub fn sample_position(&self, x: u32, y: u32, sample: u32) -> (Real, Real) {
                if self.spp == 1 {
                    return (x as Real + 0.5, y as Real + 0.5);
                }
                let h = pcg_hash(x ^ pcg_hash(y ^ pcg_hash(sample ^ pcg_hash(self.seed))));
                let (jx, jy) = (unit_float(h), unit_float(pcg_hash(h)));
                let strata_y = self.spp / self.strata_x;
                let (cx, cy) = (
                    (sample % self.strata_x) as Real,
                    (sample / self.strata_x) as Real,
                );
                (
                    x as Real + (cx + jx) / self.strata_x as Real,
                    y as Real + (cy + jy) / strata_y as Real,
                )
            }

            /// One pixel: the box-filtered mean of its samples, the primitive its
            /// first sample hit, and the variance of its mean luminance.
            #[inline(always)]
            pub fn render_pixel(&self, x: u32, y: u32) -> (Vec3, u32, Real) {
                let (sums, prim) = self.add_samples(x, y, 0..self.spp, (Vec3::ZERO, 0.0));
                let (mean, variance) = self.pixel_mean(sums);
                (mean, prim, variance)
            }

            /// `samples` of the pixel added in turn to `sums` (colour, squared
            /// luminance), and what the first of them hit. Inlined, so that
            /// in `cpu::with_simd` the traversal runs with the vector
            /// instructions: compiled on its own, the render's every node
            /// visit called `intersect_boxes_ymm`'s intrinsics one by one
            /// (the dragon's 1024² CPU render took 1.55 s, now 0.33 s).
            #[inline(always)]
            pub fn add_samples(
                &self,
                x: u32,
                y: u32,
                samples: std::ops::Range<u32>,
                sums: (Vec3, Real),
            ) -> ((Vec3, Real), u32) {
                let mut sums = sums;
                let mut first_prim = NO_HIT;
                let first = samples.start;
                for sample in samples {
                    let (px, py) = self.sample_position(x, y, sample);
                    let ray = self.camera_ray(px, py);
                    let hit = self.trace_closest(ray);
                    if sample == first {
                        first_prim = hit.prim;
                    }
                    sums = self.add_sample(sums, self.radiance(&ray, &hit, x, y, sample));
                }
                (sums, first_prim)
            }

            /// `sums` with one more sample's colour (and its squared luminance).
            pub fn add_sample(
                &self,
                (sum, sum_squares): (Vec3, Real),
                color: Vec3,
            ) -> (Vec3, Real) {
                let l = color.dot(Vec3::new(0.2126, 0.7152, 0.0722));
                (sum + color, sum_squares + l * l)
            }

            /// The pixel's mean and the variance of its mean luminance, from the
            /// sums of all the view's samples.
            pub fn pixel_mean(&self, (sum, sum_squares): (Vec3, Real)) -> (Vec3, Real) {
                let luminance = Vec3::new(0.2126, 0.7152, 0.0722);
                let spp = self.spp;
                let n = spp as Real;
                let mean = sum / n;
                let l = mean.dot(luminance);
                let variance = if spp > 1 {
                    (sum_squares - n * l * l).max(0.0) / ((n - 1.0) * n)
                } else {
                    0.0
                };
                (mean, variance)
            }
        }

        /// PCG hash (Jarzynski and Olano, JCGT 2020), as in the shader.
        pub fn pcg_hash(x: u32) -> u32 {
            let state = x.wrapping_mul(747796405).wrapping_add(2891336453);
            let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
            (word >> 22) ^ word
        }

        /// A uniform number in [0, 1) from the top 24 bits of `h`.
        fn unit_float(h: u32) -> Real {
            (h >> 8) as Real * (1.0 / 16777216.0)
        }
    };
}
pub(crate) use sample;
