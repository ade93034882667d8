//! The path integrator's light sampling, the twin of shaders/lights.wgsl,
//! function by function with the same names (docs/rendering.md, "Lights"
//! and "The environment"): an emitter picked by power from the scene's
//! emitters' table, a point or direction on it, the pdfs multiple
//! importance sampling weighs by, and the environment's radiance. The
//! same bits as the shader in f32: every operation in its order (the
//! shader's `rounded` and `opaque_copy` keep its compiler from fusing or
//! reordering, and are the identity here). Written once for both precisions:
//! `kernel!` (kernel.rs) expands it into `cpu::f32` and `cpu::f64`.

/// The stage's items, expanded into the module that invokes it (`kernel!`).
macro_rules! lights {
    () => {
        /// What `sample_emitter` gives (the shader's `EmitterSample`): the
        /// direction to the light, how far it is (`FAR`: at infinity), the
        /// radiance along it, its pdf in solid angle times the pick's
        /// probability (the probability alone for a punctual light,
        /// `delta`); pdf 0: no sample.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct EmitterSample {
            pub wi: Vec3,
            pub distance: Real,
            pub radiance: Vec3,
            pub pdf: Real,
            pub delta: bool,
        }

        impl EmitterSample {
            /// No sample, as the shader's zeroed `var` leaves it.
            const NONE: EmitterSample = EmitterSample {
                wi: Vec3::ZERO,
                distance: 0.0,
                radiance: Vec3::ZERO,
                pdf: 0.0,
                delta: false,
            };
        }

        /// The largest `Real` below 1 (pbrt's OneMinusEpsilon).
        const ONE_MINUS_EPSILON: Real = 1.0 - Real::EPSILON / 2.0;
        /// 1/(2π²): a map's pdf in (u, v) to solid angle, with 1/sin θ
        /// (1/4π, the uniform sphere's pdf, is the winding stage's).
        const INV_TWO_PI_SQUARED: Real =
            (0.5 / (std::f64::consts::PI * std::f64::consts::PI)) as Real;

        /// The shader's `triangle_solid_angle_pdf`: r²/(A·|cos θ|) =
        /// 2r²/|n·wi| for `n` the edges' cross product; 0 edge-on.
        #[inline(always)]
        fn triangle_solid_angle_pdf(n: Vec3, wi: Vec3, distance: Real) -> Real {
            let cos_area = dot_rounded(n, wi).abs();
            if cos_area == 0.0 {
                return 0.0;
            }
            2.0 * (distance * distance) / cos_area
        }

        /// The shader's `sample_light`: π·color/r² from a point or spot
        /// light (times a spot's falloff), π·color from a directional one.
        #[inline(always)]
        fn sample_light(position: Vec3, light: &crate::layout::Light) -> EmitterSample {
            let mut out = EmitterSample {
                delta: true,
                pdf: 1.0,
                ..EmitterSample::NONE
            };
            let emitted = PI * vec3(light.color);
            if light.kind == crate::layout::LIGHT_DIRECTIONAL {
                out.wi = vec3(light.vector);
                out.distance = FAR;
                out.radiance = emitted;
                return out;
            }
            let d = vec3(light.vector) - position;
            let distance_squared = dot_rounded(d, d);
            if distance_squared == 0.0 {
                out.pdf = 0.0;
                return out;
            }
            out.distance = distance_squared.sqrt();
            out.wi = d / out.distance;
            out.radiance = (emitted / distance_squared).min(Vec3::splat(FAR));
            if light.kind == crate::layout::LIGHT_SPOT {
                out.radiance *= spot_falloff(light, out.wi);
            }
            out
        }

        /// pbrt-v4's FindInterval over `size` entries of `cdf` from
        /// `start`: the last i (at most size − 2) with cdf[i] ≤ u.
        #[inline(always)]
        fn find_interval(cdf: &[f32], start: usize, size: usize, u: Real) -> usize {
            let mut first = 1;
            let mut remaining = size - 2;
            while remaining > 0 {
                let half = remaining >> 1;
                let middle = first + half;
                if cdf[start + middle] as Real <= u {
                    first = middle + 1;
                    remaining -= half + 1;
                } else {
                    remaining = half;
                }
            }
            first.clamp(1, size - 1) - 1
        }

        /// Where row `row`'s conditional CDF starts (`rows` rows of cells,
        /// `columns` columns).
        #[inline(always)]
        fn conditional_start(rows: usize, columns: usize, row: usize) -> usize {
            rows + 1 + row * (columns + 1)
        }

        /// Mitsuba 3's (u, v) of a direction in the map's frame.
        #[inline(always)]
        fn environment_uv(d: Vec3) -> Vec2 {
            let u = approx_atan2(d.x, -d.z) * INV_TWO_PI;
            Vec2::new(u - u.floor(), approx_acos(d.y) * INV_PI)
        }

        /// A map as the shader's bindings hold it: the uniform, pixels, CDFs.
        struct EnvironmentView<'s> {
            lighting: &'s crate::layout::Lighting,
            map: Option<&'s crate::lighting::EnvironmentMap>,
        }

        impl EnvironmentView<'_> {
            /// A world direction in the map's frame: turned by −rotation.
            #[inline(always)]
            fn environment_local(&self, dir: Vec3) -> Vec3 {
                let (c, s) = (
                    self.lighting.rotation_cos as Real,
                    self.lighting.rotation_sin as Real,
                );
                Vec3::new(c * dir.x - s * dir.z, dir.y, s * dir.x + c * dir.z)
            }

            /// A direction in the map's frame in the world: turned by +rotation.
            #[inline(always)]
            fn environment_world(&self, d: Vec3) -> Vec3 {
                let (c, s) = (
                    self.lighting.rotation_cos as Real,
                    self.lighting.rotation_sin as Real,
                );
                Vec3::new(c * d.x + s * d.z, d.y, c * d.z - s * d.x)
            }

            #[inline(always)]
            fn environment_texel(
                &self,
                map: &crate::lighting::EnvironmentMap,
                x: u32,
                y: u32,
            ) -> Vec3 {
                let p = map.pixels[(y * self.lighting.environment_width + x) as usize];
                vec3([p[0], p[1], p[2]])
            }

            /// The map at (u, v), bilinear as Mitsuba reads it.
            #[inline(always)]
            fn environment_lookup(&self, uv: Vec2) -> Vec3 {
                let map = self.map.expect("a map");
                let width = self.lighting.environment_width;
                let height = self.lighting.environment_height;
                let x = uv.x * width as Real - 0.5;
                let y = uv.y.clamp(0.0, 1.0) * (height - 1) as Real;
                let x0 = x.floor();
                let y0 = y.floor().min((height - 2) as Real);
                let (fx, fy) = (x - x0, y - y0);
                let c0 = (x0 as i32 + width as i32) as u32 % width;
                let c1 = (c0 + 1) % width;
                let r0 = y0 as u32;
                let texel = |x, y| self.environment_texel(map, x, y);
                let top = (1.0 - fx) * texel(c0, r0) + fx * texel(c1, r0);
                let bottom = (1.0 - fx) * texel(c0, r0 + 1) + fx * texel(c1, r0 + 1);
                (1.0 - fy) * top + fy * bottom
            }

            /// The shader's `environment_radiance`, the scene having one.
            #[inline(always)]
            fn environment_radiance(&self, dir: Vec3) -> Vec3 {
                if self.map.is_none() {
                    return vec3(self.lighting.environment_color);
                }
                self.environment_lookup(environment_uv(self.environment_local(dir)))
            }

            /// The shader's `sample_environment`.
            fn sample_environment(&self, u: Vec2) -> EmitterSample {
                let mut out = EmitterSample {
                    distance: FAR,
                    ..EmitterSample::NONE
                };
                let Some(map) = self.map else {
                    let z = 1.0 - 2.0 * u.x;
                    let r = safe_sqrt(1.0 - z * z);
                    let (sin, cos) = approx_sin_cos(TWO_PI * u.y);
                    out.wi = Vec3::new(r * cos, r * sin, z);
                    out.radiance = vec3(self.lighting.environment_color);
                    out.pdf = INV_FOUR_PI;
                    return out;
                };
                let cdf = &map.cdf;
                let columns = self.lighting.environment_width as usize;
                let rows = self.lighting.environment_height as usize - 1;
                let row = find_interval(cdf, 0, rows + 1, u.y);
                let m0 = cdf[row] as Real;
                let dm = cdf[row + 1] as Real - m0;
                let start = conditional_start(rows, columns, row);
                let column = find_interval(cdf, start, columns + 1, u.x);
                let c0 = cdf[start + column] as Real;
                let dc = cdf[start + column + 1] as Real - c0;
                if !(dm > 0.0 && dc > 0.0) {
                    return out;
                }
                let t = (row as Real + (u.y - m0) / dm) / rows as Real;
                let s = (column as Real + (u.x - c0) / dc) / columns as Real;
                // Cell j starts at texel j's centre.
                let mut map_u = s + 0.5 / columns as Real;
                if map_u >= 1.0 {
                    map_u -= 1.0;
                }
                let (sin_theta, cos_theta) = approx_sin_cos(PI * t);
                let (sin_phi, cos_phi) = approx_sin_cos(TWO_PI * map_u);
                if sin_theta.is_nan() || sin_theta <= 0.0 {
                    return out;
                }
                let d = Vec3::new(sin_phi * sin_theta, cos_theta, -(cos_phi * sin_theta));
                out.wi = self.environment_world(d);
                out.radiance = self.environment_lookup(Vec2::new(map_u, t));
                let pdf_uv = (dm * rows as Real) * (dc * columns as Real);
                out.pdf = pdf_uv * INV_TWO_PI_SQUARED / sin_theta;
                out
            }

            /// The shader's `environment_pdf`, the scene having one.
            fn environment_pdf(&self, dir: Vec3) -> Real {
                let pmf = self.lighting.environment_pmf as Real;
                let Some(map) = self.map else {
                    return INV_FOUR_PI * pmf;
                };
                let d = self.environment_local(dir);
                let uv = environment_uv(d);
                let cdf = &map.cdf;
                let columns = self.lighting.environment_width as usize;
                let rows = self.lighting.environment_height as usize - 1;
                let mut s = uv.x - 0.5 / columns as Real;
                if s < 0.0 {
                    s += 1.0;
                }
                let column = ((s * columns as Real) as usize).min(columns - 1);
                let row = ((uv.y * rows as Real) as usize).min(rows - 1);
                let start = conditional_start(rows, columns, row);
                let dm = cdf[row + 1] as Real - cdf[row] as Real;
                let dc = cdf[start + column + 1] as Real - cdf[start + column] as Real;
                let sin_theta = safe_sqrt(d.x * d.x + d.z * d.z);
                if sin_theta.is_nan() || sin_theta <= 0.0 {
                    return 0.0;
                }
                let pdf_uv = (dm * rows as Real) * (dc * columns as Real);
                pdf_uv * INV_TWO_PI_SQUARED / sin_theta * pmf
            }
        }

        impl<'a> Kernel<'a> {
            /// The emission at (u, v) of triangle `prim`: its material's times
            /// its emissive texture (where it has texture coordinates).
            #[inline(always)]
            pub fn emission_at(
                &self,
                tri: &crate::layout::Triangle,
                prim: u32,
                u: Real,
                v: Real,
                dir: Vec3,
                cone_width: Real,
            ) -> Vec3 {
                let material = &self.scene.materials[tri.material as usize];
                let mut emission = vec3(material.emission);
                if material.emissive_texture != NO_TEXTURE && tri.flags & FLAG_ATTRIBUTES != 0 {
                    emission *= self
                        .texture_at(material.emissive_texture, tri, prim, u, v, dir, cone_width)
                        .truncate();
                }
                emission
            }

            fn environment_view(&self) -> Option<EnvironmentView<'_>> {
                let environment = self.scene.environment()?;
                Some(EnvironmentView {
                    lighting: &self.scene.emitters().uniform,
                    map: environment.map.as_ref(),
                })
            }

            /// The entry of the emitters' table that `u` picks (pbrt-v4's
            /// AliasTable::Sample).
            #[inline(always)]
            fn pick_emitter(&self, u: Real) -> usize {
                let entries = &self.scene.emitters().entries;
                let n = entries.len();
                let scaled = u * n as Real;
                let bin = (scaled as usize).min(n - 1);
                let rest = (scaled - bin as Real).min(ONE_MINUS_EPSILON);
                if rest < entries[bin].q as Real {
                    bin
                } else {
                    entries[bin].alias_bin as usize
                }
            }

            /// A point on triangle `prim`, uniform by area, seen from
            /// `position` (the shader's `sample_triangle`).
            fn sample_triangle(&self, position: Vec3, prim: u32, u: Vec2) -> EmitterSample {
                let mut out = EmitterSample::NONE;
                let (b0, b1) = if u.x < u.y {
                    let b0 = 0.5 * u.x;
                    (b0, u.y - b0)
                } else {
                    let b1 = 0.5 * u.y;
                    (u.x - b1, b1)
                };
                let (hu, hv) = (b1, 1.0 - b0 - b1);
                let tri = &self.scene.triangles[prim as usize];
                let (v0, v1, v2) = (vec3(tri.v0), vec3(tri.v1), vec3(tri.v2));
                let w = 1.0 - hu - hv;
                let d = w * v0 + hu * v1 + hv * v2 - position;
                let distance_squared = dot_rounded(d, d);
                if distance_squared == 0.0 {
                    return out;
                }
                out.distance = distance_squared.sqrt();
                out.wi = d / out.distance;
                out.pdf =
                    triangle_solid_angle_pdf(cross_rounded(v1 - v0, v2 - v0), out.wi, out.distance);
                if !self.cut_out(prim, hu, hv) {
                    out.radiance = self.emission_at(tri, prim, hu, hv, out.wi, 0.0);
                }
                out
            }

            /// A light for the point `position` with (shading) normal
            /// `normal`: an emitter picked by power with `u_pick`, a point or
            /// direction on it with `u`. pdf 0 where the scene has no emitter
            /// or the light is below the point's horizon.
            pub fn sample_emitter(
                &self,
                position: Vec3,
                normal: Vec3,
                u_pick: Real,
                u: Vec2,
            ) -> EmitterSample {
                let table = self.scene.emitters();
                if table.entries.is_empty() {
                    return EmitterSample::NONE;
                }
                let entry = &table.entries[self.pick_emitter(u_pick)];
                let mut out = match entry.kind {
                    crate::layout::EMITTER_TRIANGLE => {
                        self.sample_triangle(position, entry.index, u)
                    }
                    crate::layout::EMITTER_LIGHT => {
                        sample_light(position, &self.scene.lights[entry.index as usize])
                    }
                    _ => self
                        .environment_view()
                        .expect("an environment")
                        .sample_environment(u),
                };
                out.pdf *= entry.pmf as Real;
                let cos = dot_rounded(out.wi, normal);
                if cos.is_nan() || cos <= 0.0 {
                    out.pdf = 0.0;
                }
                out
            }

            /// The pdf `sample_emitter` would have given the direction `wi`
            /// to the point of triangle `hit_prim` at `distance` (0 for no
            /// emitter). `_position` is not read: area sampling needs only
            /// the distance.
            pub fn emitter_pdf(
                &self,
                _position: Vec3,
                hit_prim: u32,
                wi: Vec3,
                distance: Real,
            ) -> Real {
                let table = self.scene.emitters();
                let triangles = &table.entries[..table.uniform.num_triangle_emitters as usize];
                let Ok(entry) = triangles.binary_search_by_key(&hit_prim, |e| e.index) else {
                    return 0.0;
                };
                let tri = &self.scene.triangles[hit_prim as usize];
                let (v0, v1, v2) = (vec3(tri.v0), vec3(tri.v1), vec3(tri.v2));
                triangle_solid_angle_pdf(cross_rounded(v1 - v0, v2 - v0), wi, distance)
                    * triangles[entry].pmf as Real
            }

            /// Whether the scene has an environment (the shader's
            /// HAS_ENVIRONMENT).
            pub fn has_environment(&self) -> bool {
                self.scene.environment().is_some()
            }

            /// Whether the emitters' table holds any (the shader's
            /// HAS_EMITTERS).
            pub fn has_emitters(&self) -> bool {
                !self.scene.emitters().entries.is_empty()
            }

            /// The radiance arriving from the environment along world
            /// direction `dir`: its map's, its colour, or 0 without one.
            pub fn environment_radiance(&self, dir: Vec3) -> Vec3 {
                self.environment_view()
                    .map_or(Vec3::ZERO, |e| e.environment_radiance(dir))
            }

            /// The pdf `sample_emitter` would have given world direction
            /// `dir` by way of the environment (0 without one).
            pub fn environment_pdf(&self, dir: Vec3) -> Real {
                self.environment_view()
                    .map_or(0.0, |e| e.environment_pdf(dir))
            }
        }
    };
}
pub(crate) use lights;
