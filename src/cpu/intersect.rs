//! Intersection, the twin of shaders/intersect.wgsl: the ray/triangle tests,
//! the ray/sphere test with its error-free arithmetic, and the recording of
//! the nearest hit. Written once for both precisions: `kernel!` (kernel.rs)
//! expands it into `cpu::f32` and `cpu::f64`, whose `Real`, `Vec3` and `Vec4`
//! it takes.

/// The stage's items, expanded into the module that invokes it (`kernel!`).
macro_rules! intersect {
    () => {
        /// `record_block_hits`' `FEATURES` bits: alpha-masked triangles, spheres,
        /// and a ray/triangle test other than the watertight one.
        pub const FEATURE_ALPHA: u8 = 1;
        pub const FEATURE_SPHERES: u8 = 2;
        pub const FEATURE_OTHER_TESTS: u8 = 4;
        /// Every feature checked at run time: the generic kernel, the portable
        /// original that the specialised ones are tested against.
        pub const ALL_FEATURES: u8 = FEATURE_ALPHA | FEATURE_SPHERES | FEATURE_OTHER_TESTS;

        pub fn miss() -> Hit {
            Hit {
                t: FAR,
                prim: NO_HIT,
                u: 0.0,
                v: 0.0,
            }
        }

        impl<'a> Kernel<'a> {
            /// The scene's ray/triangle test.
            #[inline(always)]
            pub fn intersect_triangle(
                &self,
                ray: &Ray,
                shear: &Shear,
                a: Vec3,
                b: Vec3,
                c: Vec3,
            ) -> (Real, Real, Real) {
                match self.intersect {
                    Intersect::Seed => intersect_triangle_seed(ray, a, b, c),
                    Intersect::MollerTrumbore => intersect_triangle_moller_trumbore(ray, a, b, c),
                    Intersect::Watertight => intersect_triangle_watertight(ray, shear, a, b, c),
                }
            }

            /// (t, u, v) of primitive `prim` (triangles first, then spheres).
            #[inline(always)]
            pub fn intersect_primitive(
                &self,
                ray: &Ray,
                shear: &Shear,
                prim: u32,
            ) -> (Real, Real, Real) {
                let triangles = &self.scene.triangles;
                if (prim as usize) < triangles.len() {
                    let tri = &triangles[prim as usize];
                    return self.intersect_triangle(
                        ray,
                        shear,
                        vec3(tri.v0),
                        vec3(tri.v1),
                        vec3(tri.v2),
                    );
                }
                let sphere = &self.scene.spheres[prim as usize - triangles.len()];
                (
                    intersect_sphere(ray, vec3(sphere.center), sphere.radius as Real),
                    0.0,
                    0.0,
                )
            }

            /// The texture in `slot` at (u, v) of triangle `prim` (with
            /// FLAG_ATTRIBUTES), at the level of detail of a ray cone `cone_width`
            /// wide there along `dir`; width 0 reads the base level (the any-hit
            /// test's alpha). In this precision throughout: the oracle's texture
            /// coordinates are f64's.
            #[allow(clippy::too_many_arguments)]
            #[inline(always)]
            pub fn texture_at(
                &self,
                slot: u32,
                tri: &crate::layout::Triangle,
                prim: u32,
                u: Real,
                v: Real,
                dir: Vec3,
                cone_width: Real,
            ) -> Vec4 {
                let a = &self.scene.attributes[prim as usize];
                let uvs = a.uvs.map(|c| Vec2::new(c[0] as Real, c[1] as Real));
                let uv = interpolate_uv(uvs[0], uvs[1], uvs[2], u, v);
                let lod = if cone_width > 0.0 {
                    self.textures.texture_lod(
                        slot,
                        vec3(tri.v0),
                        vec3(tri.v1),
                        vec3(tri.v2),
                        uvs[0],
                        uvs[1],
                        uvs[2],
                        dir,
                        cone_width,
                    )
                } else {
                    0
                };
                self.textures.sample_texture(slot, uv, lod)
            }

            /// The base colour at (u, v) of triangle `prim`: its material's, times
            /// its corners' colours interpolated (FLAG_ATTRIBUTES), times its base
            /// colour texture (RGBA) and its alpha texture's alpha, read as
            /// `texture_at` does.
            #[inline(always)]
            pub fn base_color_at(
                &self,
                tri: &crate::layout::Triangle,
                prim: u32,
                u: Real,
                v: Real,
                dir: Vec3,
                cone_width: Real,
            ) -> Vec4 {
                let scene = self.scene;
                let material = &scene.materials[tri.material as usize];
                let mut color = vec4(material.base_color);
                if tri.flags & FLAG_ATTRIBUTES != 0 {
                    let a = &scene.attributes[prim as usize];
                    // Each product and sum rounded on its own, in this order, as
                    // the shader's (`rounded` there stops its compiler fusing or
                    // reordering them).
                    let w = Vec4::splat((1.0 - u) - v);
                    let c = |k: usize| vec4(a.colors[k]);
                    color *= w * c(0) + (Vec4::splat(u) * c(1) + Vec4::splat(v) * c(2));
                    if material.base_color_texture != NO_TEXTURE {
                        color *= self.texture_at(
                            material.base_color_texture,
                            tri,
                            prim,
                            u,
                            v,
                            dir,
                            cone_width,
                        );
                    }
                    if material.alpha_texture != NO_TEXTURE {
                        color.w *= self
                            .texture_at(material.alpha_texture, tri, prim, u, v, dir, cone_width)
                            .w;
                    }
                }
                color
            }

            /// The `FEATURES` this kernel's scene needs: a bit for each of
            /// alpha masks, spheres and another triangle test that it has.
            pub fn features(&self) -> u8 {
                let mut features = 0;
                if self.alpha_mask {
                    features |= FEATURE_ALPHA;
                }
                if !self.scene.spheres.is_empty() {
                    features |= FEATURE_SPHERES;
                }
                if self.intersect != Intersect::Watertight {
                    features |= FEATURE_OTHER_TESTS;
                }
                features
            }

            /// Whether a hit at (u, v) of `prim` falls in an alpha-masked
            /// triangle's cut-out: the shader's any-hit test, where hits are
            /// recorded (opaque triangles pay a flag test; scenes without masks,
            /// `alpha_mask` false, nothing).
            #[inline(always)]
            pub fn cut_out(&self, prim: u32, u: Real, v: Real) -> bool {
                if !self.alpha_mask {
                    return false;
                }
                let Some(tri) = self.scene.triangles.get(prim as usize) else {
                    return false;
                };
                if tri.flags & FLAG_MASKED == 0 {
                    return false;
                }
                let cutoff = self.scene.materials[tri.material as usize].alpha_cutoff as Real;
                self.base_color_at(tri, prim, u, v, Vec3::ZERO, 0.0).w < cutoff
            }

            /// Tests `prim`; if it is hit nearer than ray.tmax, makes it the hit and
            /// shortens the ray. Returns whether it did.
            #[inline(always)]
            pub fn record_hit(
                &self,
                ray: &mut Ray,
                shear: &Shear,
                hit: &mut Hit,
                prim: u32,
            ) -> bool {
                let (t, u, v) = self.intersect_primitive(ray, shear, prim);
                if t < ray.tmax && !self.cut_out(prim, u, v) {
                    ray.tmax = t;
                    *hit = Hit { t, prim, u, v };
                    return true;
                }
                false
            }

            /// `record_block_hits`' triangle lanes, in lane order; with `MASKED`,
            /// a hit in a cut-out is passed over.
            #[inline(always)]
            fn record_lanes<const MASKED: bool>(
                &self,
                ray: &mut Ray,
                hit: &mut Hit,
                block: &PrimBlock,
                lanes: &BlockHits,
                num_triangles: u32,
            ) -> bool {
                let mut recorded = false;
                for (lane, &t) in lanes.t.to_array().iter().enumerate() {
                    // Only triangle lanes (the id test also drops empty ones): a
                    // GPU that fuses multiply-adds can see a hit in a lane of
                    // zero vertices.
                    if t < ray.tmax && block.prims[lane] < num_triangles {
                        let (u, v) = lanes.uv(lane);
                        if MASKED && self.cut_out(block.prims[lane], u, v) {
                            continue;
                        }
                        ray.tmax = t;
                        *hit = Hit {
                            t,
                            prim: block.prims[lane],
                            u,
                            v,
                        };
                        recorded = true;
                    }
                }
                recorded
            }

            /// `record_lanes` with the alpha test, out of line: scenes with masks
            /// are the rare case, and the test's code inlined in the traversal
            /// loop slowed scenes without them.
            #[inline(never)]
            #[cold]
            fn record_masked_lanes(
                &self,
                ray: &mut Ray,
                hit: &mut Hit,
                block: &PrimBlock,
                lanes: &BlockHits,
                num_triangles: u32,
            ) -> bool {
                self.record_lanes::<true>(ray, hit, block, lanes, num_triangles)
            }

            /// Tests a leaf block's primitives: its triangles in one 4-lane
            /// watertight test, then (in lane order) its spheres, and its triangles
            /// too under another triangle test. Each hit nearer than ray.tmax
            /// becomes the hit and shortens the ray; returns whether there was one.
            /// `FEATURES` (`Kernel::features`) names what the scene may hold:
            /// the checks for what it lacks are compiled out, as the shader's
            /// overrides do; `ALL_FEATURES` checks them all at run time.
            #[inline(always)]
            pub fn record_block_hits<const FEATURES: u8>(
                &self,
                ray: &mut Ray,
                shear: &Shear,
                hit: &mut Hit,
                block: &PrimBlock,
            ) -> bool {
                let scene = self.scene;
                let other_tests = FEATURES & FEATURE_OTHER_TESTS != 0;
                let watertight = !other_tests || self.intersect == Intersect::Watertight;
                let mut recorded = false;
                let num_triangles = scene.triangles.len() as u32;
                if watertight && num_triangles > 0 {
                    let lanes = intersect_triangle_block(ray, shear, block);
                    // The alpha test decided once a block, not a lane: inside the
                    // lane loop, its mere presence cost camera rays 12% (callgrind:
                    // 30% more instructions in the kernel).
                    recorded = if FEATURES & FEATURE_ALPHA != 0 && self.alpha_mask {
                        self.record_masked_lanes(ray, hit, block, &lanes, num_triangles)
                    } else {
                        self.record_lanes::<false>(ray, hit, block, &lanes, num_triangles)
                    };
                }
                if (other_tests && !watertight)
                    || (FEATURES & FEATURE_SPHERES != 0 && !scene.spheres.is_empty())
                {
                    for &prim in &block.prims {
                        if prim != NO_HIT && !(watertight && prim < num_triangles) {
                            recorded |= self.record_hit(ray, shear, hit, prim);
                        }
                    }
                }
                recorded
            }
        }

        /// The lecture's test: plane hit t = n·(a − o)/(n·d), then three edge tests
        /// that must all agree in sign. Returns (t, u, v); t = FAR on a miss.
        pub fn intersect_triangle_seed(ray: &Ray, a: Vec3, b: Vec3, c: Vec3) -> (Real, Real, Real) {
            let n = (b - a).cross(c - a);
            let n_dot_d = n.dot(ray.dir);
            if n_dot_d == 0.0 {
                return NO_TRIANGLE_HIT;
            }
            let t = n.dot(a - ray.origin) / n_dot_d;
            if !(t > ray.tmin && t < ray.tmax) {
                return NO_TRIANGLE_HIT;
            }
            let p = ray.origin + t * ray.dir;
            let e0 = (b - a).cross(p - a).dot(n);
            let e1 = (c - b).cross(p - b).dot(n);
            let e2 = (a - c).cross(p - c).dot(n);
            let inside =
                (e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0) || (e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0);
            if !inside {
                return NO_TRIANGLE_HIT;
            }
            let nn = n.dot(n);
            (t, e2 / nn, e0 / nn)
        }

        const NO_TRIANGLE_HIT: (Real, Real, Real) = (FAR, 0.0, 0.0);

        /// Möller–Trumbore, with no epsilon on the determinant.
        pub fn intersect_triangle_moller_trumbore(
            ray: &Ray,
            a: Vec3,
            b: Vec3,
            c: Vec3,
        ) -> (Real, Real, Real) {
            let e1 = b - a;
            let e2 = c - a;
            let p = ray.dir.cross(e2);
            let det = e1.dot(p);
            if det == 0.0 {
                return NO_TRIANGLE_HIT;
            }
            let inv_det = 1.0 / det;
            let s = ray.origin - a;
            let u = s.dot(p) * inv_det;
            if !(0.0..=1.0).contains(&u) {
                return NO_TRIANGLE_HIT;
            }
            let q = s.cross(e1);
            let v = ray.dir.dot(q) * inv_det;
            if !(v >= 0.0 && u + v <= 1.0) {
                return NO_TRIANGLE_HIT;
            }
            let t = e2.dot(q) * inv_det;
            if !(t > ray.tmin && t < ray.tmax) {
                return NO_TRIANGLE_HIT;
            }
            (t, u, v)
        }

        #[inline(always)]
        pub fn ray_shear(dir: Vec3) -> Shear {
            let m = dir.abs();
            let kz = if m.x >= m.y && m.x >= m.z {
                0
            } else if m.y >= m.z {
                1
            } else {
                2
            };
            let mut kx = (kz + 1) % 3;
            let mut ky = (kx + 1) % 3;
            // An array, not glam's Index: its match per access is a branch that
            // mispredicts on rays of random directions.
            let d = dir.to_array();
            if d[kz] < 0.0 {
                std::mem::swap(&mut kx, &mut ky);
            }
            Shear {
                axes: [kx, ky, kz],
                s: Vec3::new(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]),
                t_scale: 1.0,
            }
        }

        /// Woop, Benthin and Wald (JCGT 2013), as in the shader: edge values of
        /// exactly 0 count as inside.
        #[inline(always)]
        pub fn intersect_triangle_watertight(
            ray: &Ray,
            shear: &Shear,
            a: Vec3,
            b: Vec3,
            c: Vec3,
        ) -> (Real, Real, Real) {
            watertight_test(ray, shear, a, b, c, false)
        }

        /// The watertight test; with `owned_edges`, an edge value of exactly 0
        /// counts only for the triangle that `owns_edge` (every-hit queries, which
        /// must count a crossing once) rather than for both.
        #[inline(always)]
        pub fn watertight_test(
            ray: &Ray,
            shear: &Shear,
            a: Vec3,
            b: Vec3,
            c: Vec3,
            owned_edges: bool,
        ) -> (Real, Real, Real) {
            let [kx, ky, kz] = shear.axes;
            // Arrays, not glam's Index (a match per access): this is the hot loop.
            let oa = (a - ray.origin).to_array();
            let ob = (b - ray.origin).to_array();
            let oc = (c - ray.origin).to_array();
            let ax = oa[kx] - shear.s.x * oa[kz];
            let ay = oa[ky] - shear.s.y * oa[kz];
            let bx = ob[kx] - shear.s.x * ob[kz];
            let by = ob[ky] - shear.s.y * ob[kz];
            let cx = oc[kx] - shear.s.x * oc[kz];
            let cy = oc[ky] - shear.s.y * oc[kz];
            // u: edge c → b, v: a → c, w: b → a.
            let u = cx * by - cy * bx;
            let v = ax * cy - ay * cx;
            let w = bx * ay - by * ax;
            if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
                return NO_TRIANGLE_HIT;
            }
            let det = u + v + w;
            if det == 0.0 {
                return NO_TRIANGLE_HIT;
            }
            if owned_edges
                && ((u == 0.0 && !owns_edge(bx - cx, by - cy, det))
                    || (v == 0.0 && !owns_edge(cx - ax, cy - ay, det))
                    || (w == 0.0 && !owns_edge(ax - bx, ay - by, det)))
            {
                return NO_TRIANGLE_HIT;
            }
            let t_scaled = u * shear.s.z * oa[kz] + v * shear.s.z * ob[kz] + w * shear.s.z * oc[kz];
            let t = t_scaled / det;
            if !(t > ray.tmin && t < ray.tmax) {
                return NO_TRIANGLE_HIT;
            }
            (t, v / det, w / det)
        }

        /// A leaf block's four lanes after `intersect_triangle_block`: t per lane
        /// (FAR where it misses), and what u and v are divided from, since only a
        /// recorded hit needs them.
        #[derive(Clone, Copy, Debug)]
        pub struct BlockHits {
            pub t: Vec4,
            v: Vec4,
            w: Vec4,
            det: Vec4,
        }

        impl BlockHits {
            /// (u, v) of lane `lane`, as `intersect_triangle_watertight` gives them.
            #[inline(always)]
            pub fn uv(&self, lane: usize) -> (Real, Real) {
                let det = self.det.to_array()[lane];
                (self.v.to_array()[lane] / det, self.w.to_array()[lane] / det)
            }
        }

        /// `intersect_triangle_watertight` on a block's four lanes at once, the
        /// same operations in the same order in each: t per lane, FAR where a lane
        /// misses (unfused arithmetic, as here, always misses a lane of zero
        /// vertices; `record_block_hits` looks only at triangle lanes).
        #[inline(always)]
        pub fn intersect_triangle_block(ray: &Ray, shear: &Shear, block: &PrimBlock) -> BlockHits {
            let [kx, ky, kz] = shear.axes;
            let origin = ray.origin.to_array();
            // Coordinate a of vertex k relative to the origin.
            let rel = |k: usize, a: usize| vec4(block.v[k][a]) - Vec4::splat(origin[a]);
            let (sx, sy, sz) = (
                Vec4::splat(shear.s.x),
                Vec4::splat(shear.s.y),
                Vec4::splat(shear.s.z),
            );
            let (az, bz, cz) = (rel(0, kz), rel(1, kz), rel(2, kz));
            let ax = rel(0, kx) - sx * az;
            let ay = rel(0, ky) - sy * az;
            let bx = rel(1, kx) - sx * bz;
            let by = rel(1, ky) - sy * bz;
            let cx = rel(2, kx) - sx * cz;
            let cy = rel(2, ky) - sy * cz;
            let u = cx * by - cy * bx;
            let v = ax * cy - ay * cx;
            let w = bx * ay - by * ax;
            let zero = Vec4::ZERO;
            let outside = (u.cmplt(zero) | v.cmplt(zero) | w.cmplt(zero))
                & (u.cmpgt(zero) | v.cmpgt(zero) | w.cmpgt(zero));
            let det = u + v + w;
            let t = (u * sz * az + v * sz * bz + w * sz * cz) / det;
            let hit = !outside
                & det.cmpne(zero)
                & t.cmpgt(Vec4::splat(ray.tmin))
                & t.cmplt(Vec4::splat(ray.tmax));
            BlockHits {
                t: Vec4::select(hit, t, Vec4::splat(FAR)),
                v,
                w,
                det,
            }
        }

        /// Nearest root of |o + t·d − c|² = r² inside (tmin, tmax); FAR on a miss.
        /// The stable form of Ray Tracing Gems ch. 7: the discriminant from the
        /// ray's distance to the centre (|f|², not b² − ac), the near root as c/q,
        /// and c itself exactly enough (`sphere_gap`) that a ray five units from a
        /// sphere of radius 1e6 gets t to 1e-5.
        pub fn intersect_sphere(ray: &Ray, center: Vec3, radius: Real) -> Real {
            let oc = ray.origin - center;
            let a = ray.dir.dot(ray.dir);
            let b = oc.dot(ray.dir);
            let c = sphere_gap(ray.origin, center, radius);
            let f = oc - (b / a) * ray.dir;
            let discriminant = a * (radius * radius - f.dot(f));
            if discriminant < 0.0 {
                return FAR;
            }
            let q = -b - sign_nonzero(b) * discriminant.sqrt();
            let t0 = c / q;
            let t1 = q / a;
            let near = t0.min(t1);
            let far = t0.max(t1);
            if near > ray.tmin && near < ray.tmax {
                return near;
            }
            if far > ray.tmin && far < ray.tmax {
                return far;
            }
            FAR
        }

        /// |o − c|² − r², to a few units in the last place of the result rather
        /// than of |o − c|²: near a large sphere the two squares agree in most of
        /// their digits (radius 1e6, five units off: 1e12 against a gap of 1e7),
        /// so each difference, square and sum keeps its rounding error
        /// (`two_sum`, `two_square`), and the errors are added back at the end.
        fn sphere_gap(origin: Vec3, center: Vec3, radius: Real) -> Real {
            let (x, ex) = two_sum(origin.x, -center.x);
            let (y, ey) = two_sum(origin.y, -center.y);
            let (z, ez) = two_sum(origin.z, -center.z);
            let (xx, exx) = two_square(x);
            let (yy, eyy) = two_square(y);
            let (zz, ezz) = two_square(z);
            let (rr, err) = two_square(radius);
            let (s1, e1) = two_sum(xx, yy);
            let (s2, e2) = two_sum(s1, zz);
            let (s3, e3) = two_sum(s2, -rr);
            // (x + ex)² = x² + 2·x·ex + ex²; ex² is below every other error here.
            let cross = 2.0 * (x * ex + y * ey + z * ez);
            s3 + (((e1 + e2) + e3) + (((exx + eyy) + ezz) - err) + cross)
        }

        /// a + b as the rounded sum and its rounding error (Knuth's TwoSum: exact
        /// without branches, whichever is larger). The shader's takes the sum
        /// through `opaque_one` (1), lest a GPU compiler fold the error to 0.
        pub fn two_sum(a: Real, b: Real) -> (Real, Real) {
            let s = a + b;
            let bb = s - a;
            (s, (a - (s - bb)) + (b - bb))
        }

        /// a² as the rounded square and its rounding error (Dekker): each product
        /// of halves is exact, so a fused multiply-add, which WGSL may or may not
        /// use, gives the same bits.
        fn two_square(a: Real) -> (Real, Real) {
            let hi = <Real as Scalar>::high_half(a);
            let lo = a - hi;
            let p = a * a;
            (p, ((hi * hi - p) + 2.0 * hi * lo) + lo * lo)
        }

        fn sign_nonzero(x: Real) -> Real {
            if x < 0.0 { -1.0 } else { 1.0 }
        }
    };
}
pub(crate) use intersect;
