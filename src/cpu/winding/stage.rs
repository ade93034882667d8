//! The stage's items for `kernel!` (src/cpu/kernel.rs), apart from
//! winding.rs's re-export of the single-precision ones, so that the
//! precisions' modules, which expand them, import nothing that imports them.

/// The stage's items, expanded into the module that invokes it (`kernel!`).
macro_rules! winding {
    () => {
        use crate::bvh::WindingTree;
        use crate::layout::Triangle;

        /// A node's dipole stands for its triangles where the point is farther
        /// from its centre than this many radii (Barill et al.'s β, 2 with their
        /// second-order terms; the first order alone needs more: at 4, points 1%
        /// of the diagonal from the dragon erred by up to 0.016, at 6 by 4.5e-3,
        /// for 2.4 times the time).
        pub const WINDING_BETA: Real = 6.0;
        /// Winding tree nodes waiting on the walk's stack at most: each visit pops
        /// one and pushes at most eight children, over at most `bvh::MAX_DEPTH`
        /// levels.
        pub const WINDING_STACK: usize = 7 * crate::bvh::MAX_DEPTH + 1;

        const INV_FOUR_PI: Real = 0.25 / PI;

        /// The solid angle of triangle (a, b, c) seen from `q`, over 4π: positive
        /// where q sees its front (the side its normal (b − a) × (c − a) points
        /// to) from behind, as a point inside a closed outward-facing mesh does.
        #[inline(always)]
        pub fn triangle_winding(q: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Real {
            let qa = a - q;
            let qb = b - q;
            let qc = c - q;
            let la = dot3(qa, qa).sqrt();
            let lb = dot3(qb, qb).sqrt();
            let lc = dot3(qc, qc).sqrt();
            let cross = Vec3::new(
                qb.y * qc.z - qb.z * qc.y,
                qb.z * qc.x - qb.x * qc.z,
                qb.x * qc.y - qb.y * qc.x,
            );
            let det = dot3(qa, cross);
            let den = la * lb * lc + dot3(qa, qb) * lc + dot3(qa, qc) * lb + dot3(qb, qc) * la;
            approx_atan2(det, den) * INV_TWO_PI
        }

        /// `triangle_winding` of four triangles at once (corners per axis, a
        /// lane a triangle): lane for lane the same IEEE operations in the same
        /// order, its branches as selects, so the same bits.
        #[inline(always)]
        pub fn triangle_winding4(q: Vec3, corners: [[Vec4; 3]; 3]) -> Vec4 {
            let sub = |v: [Vec4; 3]| {
                [
                    v[0] - Vec4::splat(q.x),
                    v[1] - Vec4::splat(q.y),
                    v[2] - Vec4::splat(q.z),
                ]
            };
            let dot = |x: [Vec4; 3], y: [Vec4; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
            let [qa, qb, qc] = corners.map(sub);
            let la = dot(qa, qa).sqrt();
            let lb = dot(qb, qb).sqrt();
            let lc = dot(qc, qc).sqrt();
            let cross = [
                qb[1] * qc[2] - qb[2] * qc[1],
                qb[2] * qc[0] - qb[0] * qc[2],
                qb[0] * qc[1] - qb[1] * qc[0],
            ];
            let det = dot(qa, cross);
            let den = la * lb * lc + dot(qa, qb) * lc + dot(qa, qc) * lb + dot(qb, qc) * la;
            // `approx_atan2`, lane by lane.
            let (ax, ay) = (den.abs(), det.abs());
            let zero = Vec4::ZERO;
            let steep = ay.cmpgt(ax);
            let hi = Vec4::select(steep, ay, ax);
            let lo = Vec4::select(steep, ax, ay);
            let z = lo / hi;
            let z2 = z * z;
            let c = Vec4::splat;
            let mut r = z
                * (c(0.999_999_94)
                    + z2 * (c(-0.333_320_95)
                        + z2 * (c(0.199_713_74)
                            + z2 * (c(-0.140_294_12)
                                + z2 * (c(0.099_427_36)
                                    + z2 * (c(-0.059_904_337)
                                        + z2 * (c(0.024_556_82) + z2 * c(-0.004_780_36))))))));
            r = Vec4::select(steep, c(HALF_PI) - r, r);
            r = Vec4::select(den.cmplt(zero), c(PI) - r, r);
            r = Vec4::select(det.cmplt(zero), -r, r);
            Vec4::select(hi.cmpeq(zero), zero, r) * c(INV_TWO_PI)
        }

        /// The far field of a node's triangles at `q`: n · (centre − q) / (4π
        /// |centre − q|³), n the sum of their area vectors.
        #[inline(always)]
        pub fn dipole_winding(q: Vec3, centre: Vec3, normal: Vec3) -> Real {
            let d = centre - q;
            let r2 = dot3(d, d);
            let r = r2.sqrt();
            dot3(normal, d) / (r2 * r) * INV_FOUR_PI
        }

        /// a + b and its rounding error (`two_sum`): the walk's sum carries its
        /// error along, so that thousands of terms (stacked layers) round no worse
        /// than a few. The shader has its own: its `two_sum` takes the sum through
        /// `opaque_one`, which is 0 in a scene without spheres, as a winding
        /// query's scene is.
        #[inline(always)]
        pub fn winding_sum(a: Real, b: Real) -> (Real, Real) {
            two_sum(a, b)
        }

        /// The generalized winding number of the triangles at `q` (local frame):
        /// the tree from the root, a node's dipole where q is beyond
        /// `WINDING_BETA` radii of it, else its leaves' triangles exactly and its
        /// children in turn (pushed in order, so taken last first), summed with
        /// their rounding errors (`winding_sum`).
        pub fn winding_number(tree: &WindingTree, triangles: &[Triangle], q: Vec3) -> Real {
            let mut w = 0.0;
            let mut error = 0.0;
            if tree.nodes.is_empty() {
                return w;
            }
            let mut stack = [0u32; WINDING_STACK];
            let mut sp = 1;
            while sp > 0 {
                sp -= 1;
                let node = &tree.nodes[stack[sp] as usize];
                let centre = vec3(node.centre);
                let d = centre - q;
                let reach = WINDING_BETA * node.radius as Real;
                if dot3(d, d) > reach * reach {
                    let (sum, e) = winding_sum(w, dipole_winding(q, centre, vec3(node.normal)));
                    w = sum;
                    error += e;
                    continue;
                }
                let prims = &tree.prims
                    [node.first_prim as usize..(node.first_prim + node.prim_count) as usize];
                if EXACT {
                    // The oracle's exact atan has no four-lane form.
                    for &prim in prims {
                        let t = &triangles[prim as usize];
                        let winding = triangle_winding(q, vec3(t.v0), vec3(t.v1), vec3(t.v2));
                        let (sum, e) = winding_sum(w, winding);
                        w = sum;
                        error += e;
                    }
                } else {
                    // Four triangles at a time (the last group's spare lanes
                    // repeat its first), summed in order as one at a time.
                    for group in prims.chunks(4) {
                        let t = |k: usize| &triangles[group[k.min(group.len() - 1)] as usize];
                        let corners = |v: fn(&Triangle) -> [f32; 3]| {
                            let [t0, t1, t2, t3] = [t(0), t(1), t(2), t(3)].map(v);
                            [0, 1, 2].map(|a| vec4([t0[a], t1[a], t2[a], t3[a]]))
                        };
                        let windings = triangle_winding4(
                            q,
                            [corners(|t| t.v0), corners(|t| t.v1), corners(|t| t.v2)],
                        )
                        .to_array();
                        for &winding in &windings[..group.len()] {
                            let (sum, e) = winding_sum(w, winding);
                            w = sum;
                            error += e;
                        }
                    }
                }
                for child in node.first_child..node.first_child + node.child_count {
                    stack[sp] = child;
                    sp += 1;
                }
            }
            w + error
        }
    };
}
pub(crate) use winding;
