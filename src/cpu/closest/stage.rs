//! The stage's items for `kernel!` (src/cpu/kernel.rs), apart from
//! closest.rs's re-export of the single-precision ones, so that the
//! precisions' modules, which expand them, import nothing that imports them.

/// The stage's items, expanded into the module that invokes it (`kernel!`).
macro_rules! closest {
    () => {
        use crate::bvh::Bvh;
        use crate::cpu::lanes::Lanes;

        /// The nearest point found for a query point: its squared distance, the
        /// triangle, (u, v) on it, and the point itself (all in the scene's local
        /// frame).
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct Nearest {
            pub d2: Real,
            pub prim: u32,
            pub u: Real,
            pub v: Real,
            pub point: Vec3,
        }

        /// a · b, summed left to right (WGSL's `dot` leaves its order open).
        #[inline(always)]
        pub fn dot3(a: Vec3, b: Vec3) -> Real {
            a.x * b.x + a.y * b.y + a.z * b.z
        }

        /// The point of segment s0 + t·e (t in [0, 1]) nearest `p`: the point,
        /// its squared distance and t (0 on a segment of zero length).
        #[inline(always)]
        pub fn closest_on_segment(p: Vec3, s0: Vec3, e: Vec3) -> (Vec3, Real, Real) {
            let ee = dot3(e, e);
            let mut t = 0.0;
            if ee > 0.0 {
                t = (dot3(p - s0, e) / ee).clamp(0.0, 1.0);
            }
            let q = s0 + e * t;
            let d = p - q;
            (q, dot3(d, d), t)
        }

        /// The point of triangle (a, b, c) nearest `p`: the point, its squared
        /// distance and (u, v), the weights of b and c. Inside the triangle's
        /// prism (Ericson's region test: every barycentric area positive) the
        /// projection; else the nearest of the edges ab, ac, bc in that order,
        /// the first kept on equal distances. A degenerate triangle (zero area)
        /// takes its edges too, so nothing divides by zero.
        #[inline(always)]
        pub fn closest_point_triangle(
            p: Vec3,
            a: Vec3,
            b: Vec3,
            c: Vec3,
        ) -> (Vec3, Real, Real, Real) {
            let ab = b - a;
            let ac = c - a;
            let ap = p - a;
            let bp = p - b;
            let cp = p - c;
            let d1 = dot3(ab, ap);
            let d2 = dot3(ac, ap);
            let d3 = dot3(ab, bp);
            let d4 = dot3(ac, bp);
            let d5 = dot3(ab, cp);
            let d6 = dot3(ac, cp);
            let va = d3 * d6 - d5 * d4;
            let vb = d5 * d2 - d1 * d6;
            let vc = d1 * d4 - d3 * d2;
            let sum = va + vb + vc;
            if va > 0.0 && vb > 0.0 && vc > 0.0 && sum > 0.0 {
                let v = vb / sum;
                let w = vc / sum;
                let q = a + ab * v + ac * w;
                let d = p - q;
                return (q, dot3(d, d), v, w);
            }
            let (mut q, mut best, t) = closest_on_segment(p, a, ab);
            let (mut u, mut v) = (t, 0.0);
            let (q2, d2_ac, t2) = closest_on_segment(p, a, ac);
            if d2_ac < best {
                (q, best, u, v) = (q2, d2_ac, 0.0, t2);
            }
            let (q3, d2_bc, t3) = closest_on_segment(p, b, c - b);
            if d2_bc < best {
                (q, best, u, v) = (q3, d2_bc, 1.0 - t3, t3);
            }
            (q, best, u, v)
        }

        /// The squared distance from `p` to the box (lo, hi): 0 inside.
        #[inline(always)]
        pub fn box_distance2(p: Vec3, lo: Vec3, hi: Vec3) -> Real {
            let d = (lo - p).max(p - hi).max(Vec3::ZERO);
            dot3(d, d)
        }

        /// Whether a candidate at squared distance `d2` on triangle `prim` beats
        /// the best so far: nearer, or as near with a lower id (so that shared
        /// edges and vertices go to the same triangle whatever the order of
        /// visits).
        #[inline(always)]
        pub fn better(d2: Real, prim: u32, best_d2: Real, best_prim: u32) -> bool {
            d2 < best_d2 || (d2 == best_d2 && prim < best_prim)
        }

        /// The squared distance beyond which a box can hold no candidate as good
        /// as one at squared distance `d2`: (√d2 + margin)², where `margin`
        /// bounds the rounding of a candidate's distance and of a box's (see
        /// `query_margin`).
        #[inline(always)]
        pub fn cull_bound(d2: Real, margin: Real) -> Real {
            let d = d2.sqrt() + margin;
            d * d
        }

        /// How far a computed distance may be from the exact one for a point of
        /// largest coordinate `point_extent` in a scene of radius `scene_radius`
        /// (local frame): a few hundred units in the last place of the largest
        /// coordinate involved, far more than the few that the arithmetic loses.
        pub fn query_margin(point_extent: Real, scene_radius: Real) -> Real {
            1e-5 * point_extent.max(scene_radius)
        }

        /// `closest_point_triangle` on a leaf block's four lanes at once
        /// (`closest_point_lanes`). Returns (d², u, v) per lane and the
        /// points' coordinates per axis.
        #[inline(always)]
        pub fn closest_point_block(p: Vec3, block: &PrimBlock) -> (Vec4, Vec4, Vec4, [Vec4; 3]) {
            let v = |i: usize| -> [Vec4; 3] { std::array::from_fn(|k| vec4(block.v[i][k])) };
            closest_point_lanes(p, [v(0), v(1), v(2)])
        }

        /// `closest_point_triangle` on triangles (a, b, c) in lanes: the same
        /// operations in the same order in each lane (SSE's are IEEE's, so the
        /// same bits as the scalar function and the shader), the interior and
        /// the three edges all computed and the answer selected as the scalar
        /// function's branches choose it. Returns (d², u, v) per lane and the
        /// points' coordinates per axis.
        #[inline(always)]
        pub fn closest_point_lanes<L: Lanes<Scalar = Real>>(
            p: Vec3,
            [a, b, c]: [[L; 3]; 3],
        ) -> (L, L, L, [L; 3]) {
            // Functions, not closures, each inlined: a closure left a call
            // to every AVX intrinsic in it (a `Ymm` is f32's `Wide`).
            #[inline(always)]
            fn sub<L: Lanes>(x: [L; 3], y: [L; 3]) -> [L; 3] {
                [x[0] - y[0], x[1] - y[1], x[2] - y[2]]
            }
            #[inline(always)]
            fn dot<L: Lanes>(x: [L; 3], y: [L; 3]) -> L {
                x[0] * y[0] + x[1] * y[1] + x[2] * y[2]
            }
            /// s0 + e·t.
            #[inline(always)]
            fn along<L: Lanes>(s0: [L; 3], e: [L; 3], t: L) -> [L; 3] {
                [s0[0] + e[0] * t, s0[1] + e[1] * t, s0[2] + e[2] * t]
            }
            #[inline(always)]
            fn select<L: Lanes>(mask: L::Mask, x: [L; 3], y: [L; 3]) -> [L; 3] {
                [
                    L::select(mask, x[0], y[0]),
                    L::select(mask, x[1], y[1]),
                    L::select(mask, x[2], y[2]),
                ]
            }
            /// `closest_on_segment` in lanes.
            #[inline(always)]
            fn segment<L: Lanes<Scalar = Real>>(
                p: [L; 3],
                s0: [L; 3],
                e: [L; 3],
            ) -> ([L; 3], L, L) {
                let zero = L::splat(0.0);
                let ee = dot(e, e);
                let t = L::select(
                    ee.gt(zero),
                    (dot(sub(p, s0), e) / ee)
                        .greater(zero)
                        .lesser(L::splat(1.0)),
                    zero,
                );
                let q = along(s0, e, t);
                let d = sub(p, q);
                (q, dot(d, d), t)
            }
            let p = [L::splat(p.x), L::splat(p.y), L::splat(p.z)];
            let ab = sub(b, a);
            let ac = sub(c, a);
            let ap = sub(p, a);
            let bp = sub(p, b);
            let cp = sub(p, c);
            let d1 = dot(ab, ap);
            let d2 = dot(ac, ap);
            let d3 = dot(ab, bp);
            let d4 = dot(ac, bp);
            let d5 = dot(ab, cp);
            let d6 = dot(ac, cp);
            let va = d3 * d6 - d5 * d4;
            let vb = d5 * d2 - d1 * d6;
            let vc = d1 * d4 - d3 * d2;
            let sum = va + vb + vc;
            let zero = L::splat(0.0);
            let interior = va.gt(zero) & vb.gt(zero) & vc.gt(zero) & sum.gt(zero);
            // Few blocks hold a triangle the point projects into: their
            // projection only where one does.
            let (iv, iw, iq, id2) = if L::any(interior) {
                let iv = vb / sum;
                let iw = vc / sum;
                let iq = along(along(a, ab, iv), ac, iw);
                let id = sub(p, iq);
                (iv, iw, iq, dot(id, id))
            } else {
                (zero, zero, [zero; 3], zero)
            };
            let (mut q, mut best, t1) = segment(p, a, ab);
            let (mut u, mut w) = (t1, zero);
            let (q2, d2_ac, t2) = segment(p, a, ac);
            let nearer = d2_ac.lt(best);
            q = select(nearer, q2, q);
            best = L::select(nearer, d2_ac, best);
            u = L::select(nearer, zero, u);
            w = L::select(nearer, t2, w);
            let (q3, d2_bc, t3) = segment(p, b, sub(c, b));
            let nearer = d2_bc.lt(best);
            q = select(nearer, q3, q);
            best = L::select(nearer, d2_bc, best);
            u = L::select(nearer, L::splat(1.0) - t3, u);
            w = L::select(nearer, t3, w);
            (
                L::select(interior, id2, best),
                L::select(interior, iv, u),
                L::select(interior, iw, w),
                select(interior, iq, q),
            )
        }

        /// Takes the lanes of a block test (`closest_point_lanes`) whose
        /// triangles (`prims`, the ids of `triangle_count` and above
        /// padding) beat `best`, and shrinks `bound` to the best's.
        #[inline(always)]
        fn take_nearest<L: Lanes<Scalar = Real>>(
            (d2, u, v, q): (L, L, L, [L; 3]),
            prims: &[u32],
            triangle_count: usize,
            margin: Real,
            best: &mut Nearest,
            bound: &mut Real,
        ) {
            // Most blocks hold nothing as near as the best so far: one
            // branch on all the lanes, not one on each.
            if !L::any(d2.le(L::splat(best.d2))) {
                return;
            }
            let (d2, u, v) = (d2.to_lanes(), u.to_lanes(), v.to_lanes());
            let [qx, qy, qz] = q;
            let (qx, qy, qz) = (qx.to_lanes(), qy.to_lanes(), qz.to_lanes());
            let lanes = d2.as_ref().iter().zip(u.as_ref()).zip(v.as_ref());
            let points = qx.as_ref().iter().zip(qy.as_ref()).zip(qz.as_ref());
            for ((&prim, ((&d2, &u), &v)), ((&x, &y), &z)) in prims.iter().zip(lanes).zip(points) {
                if (prim as usize) < triangle_count && better(d2, prim, best.d2, best.prim) {
                    *best = Nearest {
                        d2,
                        prim,
                        u,
                        v,
                        point: Vec3::new(x, y, z),
                    };
                    *bound = cull_bound(d2, margin);
                }
            }
        }

        /// Pushes the children of `node` whose squared distances (`d2`, four
        /// slots a vector) are within `bound` onto `queue`, farthest first so
        /// that the nearest is popped first (on equal distances the higher
        /// slot first), each written straight to its place: its rank among
        /// them from a vector comparison with all eight. A branch on each
        /// child and a sort by insertion took 1.62–1.69 s for the dragon's
        /// million points against 1.46–1.48 (docs/benchmarks.md).
        #[inline(always)]
        fn push_children(queue: &mut BoxQueue, node: &BvhNode, d2: [Vec4; 2], bound: Real) {
            let bits = |mask: [u32; 2]| mask[0] | mask[1] << 4;
            let within = bits(d2.map(|d| d.cmple(Vec4::splat(bound)).bitmask())) & node.occupied;
            queue.reserve(BVH_WIDTH);
            let len = queue.len();
            let spare = queue.spare_capacity_mut();
            // In memory: a lane taken by a variable index from a register
            // compiled to a jump table.
            let (low, high) = (d2[0].to_array(), d2[1].to_array());
            let all = [
                low[0], low[1], low[2], low[3], high[0], high[1], high[2], high[3],
            ];
            let mut rest = within;
            while rest != 0 {
                let slot = rest.trailing_zeros() as usize;
                rest &= rest - 1;
                let d = all[slot];
                let s = Vec4::splat(d);
                let farther = bits(d2.map(|v| v.cmpgt(s).bitmask()));
                let level = bits(d2.map(|v| v.cmpeq(s).bitmask())) & ((1 << slot) - 1);
                let rank = ((farther | level) & within).count_ones() as usize;
                spare[rank].write((d, node.children[slot]));
            }
            // SAFETY: the ranks of the `within` children are 0..its count,
            // each written above.
            unsafe { queue.set_len(len + within.count_ones() as usize) };
        }

        /// The boxes (node or leaf references) waiting in a query's walk, with
        /// their squared distances: a stack, each node's children pushed
        /// farthest first, kept by the caller between queries so that a query
        /// allocates nothing.
        pub type BoxQueue = Vec<(Real, u32)>;

        /// The nearest point of the BVH's triangles (ids below `triangle_count`)
        /// to `p` within squared distance `max_d2` (None when none is): boxes
        /// from a stack (`queue`, emptied first), each leaf's blocks
        /// four triangles at a time, boxes beyond `cull_bound` of the best so far
        /// skipped. Depth first, each node's children nearest first (a
        /// stack, not a heap of every box met: with the hint's bound the same
        /// boxes are opened, and a stack's push and pop cost less than a
        /// heap's). `hint`, a triangle (id and vertices) likely near `p` (a
        /// neighbouring query's answer), is the first candidate: its bound prunes
        /// from the start, and as `better` orders candidates totally the answer
        /// is the same with or without it, and in any order of visits.
        /// `wide`: a leaf's two blocks tested at once, in `Scalar::Wide`'s
        /// eight lanes, or a leaf of one block with the next box when that
        /// is one too (the same answer), where `Scalar::has_wide` holds for
        /// the process's kernel; inlined into the code of a kernel that
        /// lacks it (the portable one), slowly, but the same answer. Half the
        /// leaves a query opens hold two blocks; with them in one AVX
        /// register, the dragon's million points took 1.20–1.22 s against
        /// 1.31–1.34, and with the leaves of one block paired, 2–3% less
        /// again (docs/benchmarks.md).
        #[inline(always)]
        #[allow(clippy::too_many_arguments)]
        pub fn closest_point(
            bvh: &Bvh,
            triangle_count: usize,
            p: Vec3,
            max_d2: Real,
            margin: Real,
            hint: Option<(u32, [Vec3; 3])>,
            queue: &mut BoxQueue,
            wide: bool,
        ) -> Option<Nearest> {
            let mut best = Nearest {
                d2: max_d2,
                prim: NO_HIT,
                u: 0.0,
                v: 0.0,
                point: Vec3::ZERO,
            };
            if let Some((prim, [a, b, c])) = hint {
                let (point, d2, u, v) = closest_point_triangle(p, a, b, c);
                if better(d2, prim, best.d2, best.prim) {
                    best = Nearest {
                        d2,
                        prim,
                        u,
                        v,
                        point,
                    };
                }
            }
            let mut bound = cull_bound(best.d2, margin);
            // Only where this process's CPU runs `Wide`'s instructions: a
            // safe function's flag must not reach an instruction the CPU
            // lacks (one check a query).
            let wide = wide && <Real as Scalar>::has_wide(crate::cpu::CpuKernel::active());
            queue.clear();
            let mut current = 0u32;
            loop {
                if current & LEAF_BIT == 0 {
                    let node = &bvh.nodes[current as usize];
                    let row = |r: usize, half: usize| {
                        let b = &node.bounds[r][4 * half..4 * half + 4];
                        Vec4::new(b[0] as Real, b[1] as Real, b[2] as Real, b[3] as Real)
                    };
                    let distance2 = |half: usize| {
                        let axis = |k: usize, x: Real| {
                            (row(2 * k, half) - Vec4::splat(x))
                                .max(Vec4::splat(x) - row(2 * k + 1, half))
                                .max(Vec4::ZERO)
                        };
                        let (dx, dy, dz) = (axis(0, p.x), axis(1, p.y), axis(2, p.z));
                        dx * dx + dy * dy + dz * dz
                    };
                    push_children(queue, node, [distance2(0), distance2(1)], bound);
                } else {
                    let (first, count) = leaf_range(current);
                    let blocks = &bvh.blocks[first as usize..(first + count) as usize];
                    // A leaf of one block, with the next box to open when
                    // that is a leaf of one block too (often its sibling): the
                    // two blocks at once as well. Opening that box now rather
                    // than next changes no answer (`better` is a total order).
                    let mut pair = None;
                    if wide {
                        if let [low, high] = blocks {
                            pair = Some([low, high]);
                        } else if let ([low], Some(&(d2, next))) = (blocks, queue.last()) {
                            if next & LEAF_BIT != 0 && d2 <= bound && leaf_range(next).1 == 1 {
                                queue.pop();
                                pair = Some([low, &bvh.blocks[leaf_range(next).0 as usize]]);
                            }
                        }
                    }
                    match pair {
                        Some([low, high]) => {
                            let prims: [u32; 8] = std::array::from_fn(|i| {
                                if i < 4 {
                                    low.prims[i]
                                } else {
                                    high.prims[i - 4]
                                }
                            });
                            // SAFETY: `wide` holds only where the CPU runs
                            // the process's kernel, which has_wide allows.
                            let v = unsafe { <Real as Scalar>::wide_vertices(low, high) };
                            let lanes = closest_point_lanes(p, v);
                            take_nearest(
                                lanes,
                                &prims,
                                triangle_count,
                                margin,
                                &mut best,
                                &mut bound,
                            );
                        }
                        None => {
                            for block in blocks {
                                let lanes = closest_point_block(p, block);
                                take_nearest(
                                    lanes,
                                    &block.prims,
                                    triangle_count,
                                    margin,
                                    &mut best,
                                    &mut bound,
                                );
                            }
                        }
                    }
                }
                // The last box pushed that the best so far leaves within the bound.
                loop {
                    match queue.pop() {
                        Some((d2, child)) if d2 <= bound => {
                            current = child;
                            break;
                        }
                        Some(_) => {}
                        None => return (best.prim != NO_HIT).then_some(best),
                    }
                }
            }
        }
    };
}
pub(crate) use closest;
