//! Every hit along a ray, the twin of shaders/all_hits.wgsl: `crossing` (the
//! watertight test's arithmetic, as `intersect_triangle_watertight`, with the
//! rule `owns_edge` for a ray through an edge or a vertex) and the traversal
//! that reports every crossing in (tmin, tmax) without shrinking tmax. The
//! CPU walks its own 256-byte nodes, the GPU its compressed ones: the set of
//! crossings is the same, and the drivers sort each ray's by (t, prim).
//! Written once for both precisions: `kernel!` (kernel.rs) expands it into
//! `cpu::f32` and `cpu::f64`, whose `Real`, `Vec3` and `Vec4` it takes.

/// The stage's items, expanded into the module that invokes it (`kernel!`).
macro_rules! all_hits {
    () => {
        /// Whether a crossing exactly on the edge whose sheared direction is
        /// (dx, dy) belongs to this triangle (`det` its orientation seen along the
        /// ray): the rasteriser's top-left rule. Two triangles sharing the edge
        /// and facing the same way run it in opposite directions, so exactly one
        /// owns it; at a vertex, one triangle of a fan owns both its edges there.
        /// Where they face opposite ways (the ray grazes a fold) both or neither
        /// do, so the count's parity is right either way. An edge seen end on
        /// (dx = dy = 0) is owned by neither.
        #[inline(always)]
        pub fn owns_edge(dx: Real, dy: Real, det: Real) -> bool {
            let (x, y) = if det < 0.0 { (-dx, -dy) } else { (dx, dy) };
            y > 0.0 || (y == 0.0 && x < 0.0)
        }

        /// (t, u, v) where the ray crosses triangle (a, b, c) in (tmin, tmax), t
        /// = FAR where it does not: the watertight test (so the same t, u and v),
        /// and where an edge value is exactly 0, the crossing counts only for the
        /// triangle that `owns_edge`.
        #[inline(always)]
        pub fn crossing(ray: &Ray, shear: &Shear, a: Vec3, b: Vec3, c: Vec3) -> (Real, Real, Real) {
            watertight_test(ray, shear, a, b, c, true)
        }

        /// Whether the ray enters box (lo, hi) grown by `pad` on every side
        /// within (tmin, tmax). Grown, unlike the trace's slab test: a ray lying
        /// in a box's plane (a direction component of 0, as along a mesh's edges)
        /// must enter both boxes that meet there, since the crossing belongs to
        /// one triangle only (`owns_edge`), which may be in either.
        #[inline(always)]
        pub fn enters_padded_box(ray: &Ray, inv_dir: Vec3, lo: Vec3, hi: Vec3, pad: Real) -> bool {
            let t0 = (lo - Vec3::splat(pad) - ray.origin) * inv_dir;
            let t1 = (hi + Vec3::splat(pad) - ray.origin) * inv_dir;
            let near = t0.min(t1).max_element().max(ray.tmin);
            let far = t0.max(t1).min_element().min(ray.tmax);
            near <= far
        }

        impl<'a> Kernel<'a> {
            /// Calls `found` with every crossing of the ray (as given to `trace`)
            /// with a triangle in (tmin, tmax), in no particular order: the BVH's
            /// boxes (grown by `pad`, `enters_padded_box`) the ray enters, tmax
            /// never shrunk.
            pub fn all_hits(&self, ray_in: Ray, pad: Real, mut found: impl FnMut(Hit)) {
                let (ray, shear) = prepare_ray(ray_in);
                // Tiny components as the trace's slab test takes them: the
                // reciprocals stay finite.
                let inv_dir = Vec3::from_array(ray.dir.to_array().map(|d| {
                    if d.abs() < MIN_SLAB_DIR {
                        MIN_SLAB_DIR.copysign(d)
                    } else {
                        d
                    }
                }))
                .recip();
                let bvh = &self.scene.bvh;
                let triangles = self.scene.triangles.len();
                let mut stack = [0u32; STACK_SIZE];
                let mut sp = 1;
                while sp > 0 {
                    sp -= 1;
                    let child = stack[sp];
                    if child & LEAF_BIT == 0 {
                        let node = &bvh.nodes[child as usize];
                        for slot in 0..BVH_WIDTH {
                            let (lo, hi) = node.child_bounds(slot);
                            if node.occupied >> slot & 1 == 1
                                && enters_padded_box(&ray, inv_dir, vec3(lo), vec3(hi), pad)
                            {
                                stack[sp] = node.children[slot];
                                sp += 1;
                            }
                        }
                        continue;
                    }
                    let (first, count) = leaf_range(child);
                    for block in &bvh.blocks[first as usize..(first + count) as usize] {
                        for lane in 0..4 {
                            let prim = block.prims[lane];
                            if prim as usize >= triangles {
                                continue;
                            }
                            let vertex = |k: usize| {
                                vec3([
                                    block.v[k][0][lane],
                                    block.v[k][1][lane],
                                    block.v[k][2][lane],
                                ])
                            };
                            let (t, u, v) = crossing(&ray, &shear, vertex(0), vertex(1), vertex(2));
                            if t < FAR {
                                found(unscale(Hit { t, prim, u, v }, &shear));
                            }
                        }
                    }
                }
            }
        }
    };
}
pub(crate) use all_hits;
