//! Coherent rays in packets: `PACKET` rays of a query (neighbours in the
//! query's order: a row of camera rays; `trace_packets`) or of a render's
//! row (`render_row`) traverse the BVH together, with
//! the single-ray kernel (`f32::Kernel::visit`) as the portable original
//! they must equal bit for bit (tests/cpu_packets.rs).
//!
//! Per node, one slab test of the packet's interval bounds (its rays'
//! reciprocal directions and offsets, each the least or greatest over the
//! packet) against the eight children says which children some ray may
//! enter; only those are tested ray by ray, the packet's rays in vector
//! lanes, with each ray's own arithmetic (so each ray's entry distance is
//! the bits `intersect_boxes` gives it). A leaf's blocks are tested for the
//! rays that enter it, each with `intersect_triangle_block` as alone.
//!
//! Why the hits are the single-ray kernel's: a ray of the packet tests
//! every box and triangle it tests alone, and more (a box is entered at a
//! distance up to its tmax, not only below it); the closest hit among them
//! is the same hit unless two are at the same distance, where the single
//! ray keeps whichever its own order met first. So a ray that meets a
//! second hit at its closest distance is traced again alone. An any-hit
//! ray's answer is its first hit in its own order: `out_of_order` says
//! where the packet's order may differ, and such a hit is traced again.

use super::f32;
use crate::layout::{self, BVH_WIDTH, LEAF_BIT, NO_HIT, leaf_range};

#[cfg(target_arch = "x86_64")]
mod load_ymm;
mod order;

/// Rays a packet traces together: one 8-lane vector of each ray quantity.
pub(super) const PACKET: usize = 8;

/// A packet's rays, one lane each (a structure of arrays), as `f32::ray_slabs`
/// and `f32::prepare_ray` give them.
struct Packet {
    rays: [f32::Ray; PACKET],
    shears: [f32::Shear; PACKET],
    inv_dir: [[f32::Real; PACKET]; 3],
    inv_dir_far: [[f32::Real; PACKET]; 3],
    near_offset: [[f32::Real; PACKET]; 3],
    far_offset: [[f32::Real; PACKET]; 3],
    tmin: [f32::Real; PACKET],
    /// The least of `tmin`.
    tmin_least: f32::Real,
    /// Shrinks to each ray's closest hit so far.
    tmax: [f32::Real; PACKET],
    /// The packet's interval bounds, per axis: the least and greatest
    /// reciprocal direction (near and far), the least near offset and the
    /// greatest far offset.
    bounds: [[f32::Real; 6]; 3],
    /// Which plane of an axis is near: the same for every ray.
    flip: [usize; 3],
}

/// What a packet's trace found, ray by ray.
struct Found {
    hits: [f32::Hit; PACKET],
    /// The block that holds each ray's hit (`Traversal::hit_block`).
    blocks: [u32; PACKET],
    /// Rays to trace again alone: a second hit at the closest distance,
    /// or an any hit where the ray's order left the packet's.
    again: u32,
    /// The node whose subtree each ray in `again` is traced again from
    /// (the root for closest hits).
    from: [u32; PACKET],
}

/// A stack entry: a child, the rays that enter it, and where each does.
#[derive(Clone, Copy)]
struct Entry {
    child: u32,
    rays: u32,
    t: [f32::Real; PACKET],
    /// Rays suspect above the child's node (`trace_packet`'s
    /// `suspects`), and those the packet takes into the child early
    /// (`out_of_order`): suspect from that node on.
    above: u32,
    early: u32,
    /// The child's node's parent.
    parent: u32,
}

impl Packet {
    /// A packet to `load` rays into.
    #[inline(always)]
    fn new() -> Packet {
        let ray = f32::Ray {
            origin: glam::Vec3::ZERO,
            tmin: 0.0,
            dir: glam::Vec3::X,
            tmax: 0.0,
        };
        let (ray, shear) = f32::prepare_ray(ray);
        Packet {
            rays: [ray; PACKET],
            shears: [shear; PACKET],
            inv_dir: [[0.0; PACKET]; 3],
            inv_dir_far: [[0.0; PACKET]; 3],
            near_offset: [[0.0; PACKET]; 3],
            far_offset: [[0.0; PACKET]; 3],
            tmin: [0.0; PACKET],
            tmin_least: 0.0,
            tmax: [0.0; PACKET],
            bounds: [[0.0; 6]; 3],
            flip: [0; 3],
        }
    }

    /// Makes `rays` the packet's; false where their directions do not
    /// share an octant (their near planes differ) or one has a NaN, and
    /// the packet is then not traced.
    #[inline(always)]
    fn load(&mut self, rays: &[f32::Ray; PACKET]) -> bool {
        // `f32::prepare_ray` and `f32::ray_slabs`, lane by lane: the same
        // operations in the same order in each lane (so the same bits),
        // in vector registers rather than a ray at a time.
        let lanes = |f: &dyn Fn(&f32::Ray) -> f32::Real| -> [f32::Real; PACKET] {
            std::array::from_fn(|r| f(&rays[r]))
        };
        let dir = [
            lanes(&|r| r.dir.x),
            lanes(&|r| r.dir.y),
            lanes(&|r| r.dir.z),
        ];
        let origin = [
            lanes(&|r| r.origin.x),
            lanes(&|r| r.origin.y),
            lanes(&|r| r.origin.z),
        ];
        let mut up = [1.0; PACKET];
        let mut down = [1.0; PACKET];
        let mut d = [[0.0; PACKET]; 3];
        let mut kz = [0usize; PACKET];
        let mut flips = [0u32; 3];
        for r in 0..PACKET {
            // `direction_scale` of the largest component.
            let max = |a: f32::Real, b: f32::Real| if a > b { a } else { b };
            let m = max(max(dir[0][r].abs(), dir[1][r].abs()), dir[2][r].abs());
            let exponent = (m.to_bits() >> 23) & 0xff;
            if exponent != 0 && exponent < 254 {
                up[r] = f32::Real::from_bits((254 - exponent) << 23);
                down[r] = f32::Real::from_bits(exponent << 23);
            }
            for a in 0..3 {
                d[a][r] = dir[a][r] * up[r];
            }
            self.tmin[r] = rays[r].tmin * down[r];
            let tmax = rays[r].tmax * down[r];
            self.tmax[r] = if tmax < f32::FAR { tmax } else { f32::FAR };
            // `ray_shear`'s axis.
            let (x, y, z) = (d[0][r].abs(), d[1][r].abs(), d[2][r].abs());
            kz[r] = if x >= y && x >= z {
                0
            } else if y >= z {
                1
            } else {
                2
            };
            for a in 0..3 {
                let c = d[a][r];
                let clamped = if c.abs() < f32::MIN_SLAB_DIR {
                    f32::MIN_SLAB_DIR.copysign(c)
                } else {
                    c
                };
                let inv = 1.0 / clamped;
                let inv_far = inv * f32::BOX_SLACK;
                let near = -origin[a][r] * inv;
                let far = -origin[a][r] * inv_far;
                let margin = 8.0 * f32::MACHINE_EPSILON;
                self.inv_dir[a][r] = inv;
                self.inv_dir_far[a][r] = inv_far;
                self.near_offset[a][r] = near - near.abs() * margin;
                self.far_offset[a][r] = far + far.abs() * margin;
                flips[a] += (clamped < 0.0) as u32;
            }
        }
        for r in 0..PACKET {
            let kz = kz[r];
            let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
            let dz = d[kz][r];
            if dz < 0.0 {
                std::mem::swap(&mut kx, &mut ky);
            }
            self.shears[r] = f32::Shear {
                axes: [kx, ky, kz],
                s: glam::Vec3::new(d[kx][r] / dz, d[ky][r] / dz, 1.0 / dz),
                t_scale: up[r],
            };
            self.rays[r] = f32::Ray {
                origin: rays[r].origin,
                tmin: self.tmin[r],
                dir: glam::Vec3::new(d[0][r], d[1][r], d[2][r]),
                tmax: self.tmax[r],
            };
        }
        // A NaN anywhere makes its offsets or its tmin NaN.
        let mut nan = false;
        for r in 0..PACKET {
            for a in 0..3 {
                nan |= self.near_offset[a][r].is_nan() | self.far_offset[a][r].is_nan();
            }
            nan |= self.tmin[r].is_nan();
        }
        if nan || flips.iter().any(|&f| f % PACKET as u32 != 0) {
            return false;
        }
        let least = |v: &[f32::Real; PACKET]| fold(v, lesser);
        let most = |v: &[f32::Real; PACKET]| fold(v, greater);
        self.tmin_least = least(&self.tmin);
        self.flip = flips.map(|f| (f != 0) as usize);
        for a in 0..3 {
            self.bounds[a] = [
                least(&self.inv_dir[a]),
                most(&self.inv_dir[a]),
                least(&self.inv_dir_far[a]),
                most(&self.inv_dir_far[a]),
                least(&self.near_offset[a]),
                most(&self.far_offset[a]),
            ];
        }
        true
    }
}

/// `v` folded with `pick` in a halving tree, lane r against lane r +
/// width: a chain of selects would not vectorise.
#[inline(always)]
fn fold(v: &[f32::Real; PACKET], pick: fn(f32::Real, f32::Real) -> f32::Real) -> f32::Real {
    let mut v = *v;
    let mut width = PACKET / 2;
    while width > 0 {
        for r in 0..width {
            v[r] = pick(v[r], v[r + width]);
        }
        width /= 2;
    }
    v[0]
}

/// `a` where `a > b`, else `b`: SSE's maxps, `Scalar::greater_of`'s lane.
#[inline(always)]
fn greater(a: f32::Real, b: f32::Real) -> f32::Real {
    if a > b { a } else { b }
}

/// `a` where `a < b`, else `b`: minps, `Scalar::lesser_of`'s lane.
#[inline(always)]
fn lesser(a: f32::Real, b: f32::Real) -> f32::Real {
    if a < b { a } else { b }
}

impl Packet {
    /// The children of `node` that some ray of the packet may enter (up
    /// to `tmax`, the greatest of theirs), and a lower bound of where: a
    /// superset of each ray's `intersect_boxes` (a plane's distance
    /// `plane·inv_dir + offset` is monotonic in each, and rounding keeps
    /// that order, so the bounds' distances bound every ray's).
    #[inline(always)]
    fn candidates(&self, node: &layout::BvhNode, tmax: f32::Real) -> (u32, [f32::Real; BVH_WIDTH]) {
        let mut t_near = [self.tmin_least; BVH_WIDTH];
        let mut t_far = [tmax; BVH_WIDTH];
        for a in 0..3 {
            let [lo, hi, far_lo, far_hi, near_offset, far_offset] = self.bounds[a];
            let near_planes = &node.bounds[2 * a + self.flip[a]];
            let far_planes = &node.bounds[2 * a + 1 - self.flip[a]];
            for s in 0..BVH_WIDTH {
                let p = near_planes[s];
                let near = lesser(p.mul_add(lo, near_offset), p.mul_add(hi, near_offset));
                t_near[s] = greater(near, t_near[s]);
                let p = far_planes[s];
                let far = greater(p.mul_add(far_lo, far_offset), p.mul_add(far_hi, far_offset));
                t_far[s] = lesser(far, t_far[s]);
            }
        }
        let mut entered = 0;
        for s in 0..BVH_WIDTH {
            entered |= ((t_near[s] <= t_far[s] && t_near[s] <= tmax) as u32) << s;
        }
        (entered & node.occupied, t_near)
    }

    /// Which of `rays` enter child `slot` of `node` (at a distance up to
    /// their tmax; with `BELOW`, below it, as an any-hit ray alone), and
    /// where: each ray's `intersect_boxes` arithmetic in its lane.
    #[inline(always)]
    fn enter<const BELOW: bool>(
        &self,
        node: &layout::BvhNode,
        slot: usize,
        rays: u32,
    ) -> (u32, [f32::Real; PACKET]) {
        let mut t_near = self.tmin;
        let mut t_far = self.tmax;
        for a in 0..3 {
            let near_plane = node.bounds[2 * a + self.flip[a]][slot];
            let far_plane = node.bounds[2 * a + 1 - self.flip[a]][slot];
            for r in 0..PACKET {
                let near = near_plane.mul_add(self.inv_dir[a][r], self.near_offset[a][r]);
                t_near[r] = greater(near, t_near[r]);
                let far = far_plane.mul_add(self.inv_dir_far[a][r], self.far_offset[a][r]);
                t_far[r] = lesser(far, t_far[r]);
            }
        }
        let mut entered = 0;
        for r in 0..PACKET {
            let reach = if BELOW {
                t_near[r] < self.tmax[r]
            } else {
                t_near[r] <= self.tmax[r]
            };
            entered |= ((t_near[r] <= t_far[r] && reach) as u32) << r;
        }
        (entered & rays, t_near)
    }

    /// `candidates` in one 8-lane register per row (AVX2 with FMA): LLVM
    /// split the portable loop into scalar and 4-lane pieces.
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn candidates_ymm(
        &self,
        node: &layout::BvhNode,
        tmax: f32::Real,
    ) -> (u32, [f32::Real; BVH_WIDTH]) {
        use std::arch::x86_64::*;
        // SAFETY: the caller vouches for AVX2 and FMA; rows are read
        // unaligned.
        unsafe {
            let mut t_near = _mm256_set1_ps(self.tmin_least);
            let mut t_far = _mm256_set1_ps(tmax);
            for a in 0..3 {
                let [lo, hi, far_lo, far_hi, near_offset, far_offset] =
                    self.bounds[a].map(|x| _mm256_set1_ps(x));
                let p = _mm256_loadu_ps(node.bounds[2 * a + self.flip[a]].as_ptr());
                let near = _mm256_min_ps(
                    _mm256_fmadd_ps(p, lo, near_offset),
                    _mm256_fmadd_ps(p, hi, near_offset),
                );
                t_near = _mm256_max_ps(near, t_near);
                let p = _mm256_loadu_ps(node.bounds[2 * a + 1 - self.flip[a]].as_ptr());
                let far = _mm256_max_ps(
                    _mm256_fmadd_ps(p, far_lo, far_offset),
                    _mm256_fmadd_ps(p, far_hi, far_offset),
                );
                t_far = _mm256_min_ps(far, t_far);
            }
            let inside = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_LE_OQ>(t_near, t_far),
                _mm256_cmp_ps::<_CMP_LE_OQ>(t_near, _mm256_set1_ps(tmax)),
            );
            let mut t = [0.0; BVH_WIDTH];
            _mm256_storeu_ps(t.as_mut_ptr(), t_near);
            (_mm256_movemask_ps(inside) as u32 & node.occupied, t)
        }
    }

    /// `enter` with the packet's eight rays in one register (AVX2 with
    /// FMA): each lane the operations of `Scalar::intersect_boxes_ymm` for
    /// its ray, so the same bits.
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn enter_ymm<const BELOW: bool>(
        &self,
        node: &layout::BvhNode,
        slot: usize,
        rays: u32,
    ) -> (u32, [f32::Real; PACKET]) {
        use std::arch::x86_64::*;
        const { assert!(PACKET == 8) };
        // SAFETY: the caller vouches for AVX2 and FMA; the lanes are read
        // unaligned.
        unsafe {
            let load = |v: &[f32::Real; PACKET]| _mm256_loadu_ps(v.as_ptr());
            let tmax = load(&self.tmax);
            let mut t_near = load(&self.tmin);
            let mut t_far = tmax;
            for a in 0..3 {
                let near_plane = _mm256_set1_ps(node.bounds[2 * a + self.flip[a]][slot]);
                let far_plane = _mm256_set1_ps(node.bounds[2 * a + 1 - self.flip[a]][slot]);
                let near = _mm256_fmadd_ps(
                    near_plane,
                    load(&self.inv_dir[a]),
                    load(&self.near_offset[a]),
                );
                let far = _mm256_fmadd_ps(
                    far_plane,
                    load(&self.inv_dir_far[a]),
                    load(&self.far_offset[a]),
                );
                t_near = _mm256_max_ps(near, t_near);
                t_far = _mm256_min_ps(far, t_far);
            }
            let inside = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_LE_OQ>(t_near, t_far),
                if BELOW {
                    _mm256_cmp_ps::<_CMP_LT_OQ>(t_near, tmax)
                } else {
                    _mm256_cmp_ps::<_CMP_LE_OQ>(t_near, tmax)
                },
            );
            let mut t = [0.0; PACKET];
            _mm256_storeu_ps(t.as_mut_ptr(), t_near);
            (_mm256_movemask_ps(inside) as u32 & rays, t)
        }
    }

    /// The greatest tmax of the packet's rays.
    #[inline(always)]
    fn farthest(&self) -> f32::Real {
        fold(&self.tmax, greater)
    }
}

/// Traces a packet: each ray's closest hit, or with `ANY_HIT` its first
/// hit in its own order (`found.again` then names the rays whose order
/// left the packet's above their hit: `out_of_order`). Triangles alone,
/// under the watertight test (`Kernel::features` 0).
#[inline(always)]
fn trace_packet<const ANY_HIT: bool>(kernel: &f32::Kernel, p: &mut Packet, ymm: bool) -> Found {
    let bvh = &kernel.scene.bvh;
    let num_triangles = kernel.scene.triangles.len() as u32;
    let mut found = Found {
        hits: [f32::miss(); PACKET],
        blocks: [NO_HIT; PACKET],
        again: 0,
        from: [0; PACKET],
    };
    let all = (1u32 << PACKET) - 1;
    let mut stack = [std::mem::MaybeUninit::<Entry>::uninit(); crate::bvh::STACK_SIZE];
    let mut sp = 0;
    let mut child = 0;
    let mut rays = all;
    // Rays still traced: an any-hit ray leaves at its first hit in the
    // packet.
    let mut active = all;
    // Any-hit rays for which some node on the packet's path was entered
    // before a sibling the ray alone enters first (`out_of_order`): a hit
    // below it may not be the ray's first alone, so the ray is traced
    // again alone from the parent of the outermost such node
    // (`found.from`); a miss is a miss in any order.
    let mut suspects = 0u32;
    let mut tmax = p.farthest();
    loop {
        if ANY_HIT && child & LEAF_BIT != 0 {
            // The single ray's leaf step: its blocks in order, the first
            // with a hit ends its trace.
            let (first, count) = leaf_range(child);
            let blocks = &bvh.blocks[first as usize..(first + count) as usize];
            let mut each = rays & active;
            while each != 0 {
                let r = each.trailing_zeros() as usize;
                each &= each - 1;
                let mut ray = p.rays[r];
                for (b, block) in (first..).zip(blocks) {
                    if kernel.record_block_hits::<0>(
                        &mut ray,
                        &p.shears[r],
                        &mut found.hits[r],
                        block,
                    ) {
                        found.blocks[r] = b;
                        found.again |= suspects & 1 << r;
                        active &= !(1 << r);
                        break;
                    }
                }
            }
        } else if child & LEAF_BIT != 0 {
            let (first, count) = leaf_range(child);
            let blocks = &bvh.blocks[first as usize..(first + count) as usize];
            let mut each = rays;
            let mut shortened = false;
            while each != 0 {
                let r = each.trailing_zeros() as usize;
                each &= each - 1;
                // Lanes hit up to tmax itself: a lane at tmax is a tie.
                let mut ray = p.rays[r];
                ray.tmax = p.tmax[r].next_up();
                for (b, block) in (first..).zip(blocks) {
                    let lanes = f32::intersect_triangle_block(&ray, &p.shears[r], block);
                    let mut recorded = false;
                    // A lane at FAR missed, and can neither record nor tie (a
                    // ray with a hit has its tmax below FAR): camera rays 1.15×.
                    let missed = lanes.t.cmpeq(glam::Vec4::splat(f32::FAR));
                    let mut live =
                        (lanes.t.cmple(glam::Vec4::splat(p.tmax[r])) & !missed).bitmask();
                    while live != 0 {
                        let lane = live.trailing_zeros() as usize;
                        live &= live - 1;
                        let (t, prim) = (lanes.t.to_array()[lane], block.prims[lane]);
                        if !(t <= p.tmax[r] && prim < num_triangles) {
                            continue;
                        }
                        if t < p.tmax[r] {
                            let (u, v) = lanes.uv(lane);
                            p.tmax[r] = t;
                            found.hits[r] = f32::Hit { t, prim, u, v };
                            recorded = true;
                        } else if found.hits[r].prim != NO_HIT {
                            found.again |= 1 << r;
                        }
                    }
                    if recorded {
                        found.blocks[r] = b;
                        shortened = true;
                        ray.tmax = p.tmax[r].next_up();
                    }
                }
            }
            if shortened {
                tmax = p.farthest();
            }
        } else {
            let node = &bvh.nodes[child as usize];
            let (mut candidates, bound) = if ymm {
                // SAFETY: `ymm` says the CPU has AVX2 and FMA.
                #[cfg(target_arch = "x86_64")]
                unsafe {
                    p.candidates_ymm(node, tmax)
                }
                #[cfg(not(target_arch = "x86_64"))]
                unreachable!("no 8-lane registers off x86")
            } else {
                p.candidates(node, tmax)
            };
            // Entered children, nearest first by the bound of their entry
            // distances, the higher slot first on a tie as a ray alone
            // takes them (siblings often share their near plane).
            let mut order = [(0u32, 0.0 as f32::Real); BVH_WIDTH];
            // Where each ray enters each entered slot (written before read).
            let mut entries = [std::mem::MaybeUninit::<[f32::Real; PACKET]>::uninit(); BVH_WIDTH];
            let mut n = 0;
            while candidates != 0 {
                let slot = candidates.trailing_zeros() as usize;
                candidates &= candidates - 1;
                // Each candidate's node or first block starts loading now,
                // while the packet tests and orders the others: 5-7% on the
                // dragon's camera rays (docs/benchmarks.md).
                kernel.prefetch::<true>(node.children[slot]);
                let (entered, t) = if ymm {
                    // SAFETY: as above.
                    #[cfg(target_arch = "x86_64")]
                    unsafe {
                        p.enter_ymm::<ANY_HIT>(node, slot, rays)
                    }
                    #[cfg(not(target_arch = "x86_64"))]
                    unreachable!("no 8-lane registers off x86")
                } else {
                    p.enter::<ANY_HIT>(node, slot, rays)
                };
                let entered = if ANY_HIT { entered & active } else { entered };
                if entered == 0 {
                    continue;
                }
                let least = bound[slot];
                let mut j = n;
                while j > 0 && order[j - 1].1 >= least {
                    order[j] = order[j - 1];
                    j -= 1;
                }
                order[j] = (slot as u32 | entered << 8, least);
                entries[slot].write(t);
                n += 1;
            }
            let early = if ANY_HIT && n > 1 {
                if ymm {
                    // SAFETY: `ymm` says the CPU has AVX2.
                    #[cfg(target_arch = "x86_64")]
                    unsafe {
                        order::out_of_order_ymm(&order[..n], &entries)
                    }
                    #[cfg(not(target_arch = "x86_64"))]
                    unreachable!("no 8-lane registers off x86")
                } else {
                    order::out_of_order(&order[..n], &entries)
                }
            } else {
                [0; BVH_WIDTH]
            };
            if n > 0 {
                // Farthest deepest; the nearest visited at once.
                for (k, &(key, _)) in order.iter().enumerate().take(n).skip(1).rev() {
                    let slot = (key & 0xff) as usize;
                    stack[sp].write(Entry {
                        child: node.children[slot],
                        rays: key >> 8,
                        // SAFETY: written for every entered slot.
                        t: unsafe { entries[slot].assume_init() },
                        above: suspects,
                        early: early[k],
                        parent: child,
                    });
                    sp += 1;
                }
                suspect_below(&mut suspects, &mut found.from, early[0], child);
                let key = order[0].0;
                child = node.children[(key & 0xff) as usize];
                rays = key >> 8;
                continue;
            }
        }
        // The nearest pushed entry that some ray still reaches.
        let mut next = None;
        while sp > 0 {
            sp -= 1;
            // SAFETY: entries below `sp` are written.
            let entry = unsafe { stack[sp].assume_init() };
            suspects = entry.above;
            suspect_below(&mut suspects, &mut found.from, entry.early, entry.parent);
            // An any-hit ray's tmax does not move while the ray is active,
            // and its entries were pushed below it.
            let mut reach = all;
            if !ANY_HIT {
                reach = 0;
                for r in 0..PACKET {
                    reach |= ((entry.t[r] <= p.tmax[r]) as u32) << r;
                }
            }
            let reach = reach & entry.rays & active;
            if reach != 0 {
                next = Some((entry.child, reach));
                break;
            }
        }
        match next {
            Some((c, r)) => (child, rays) = (c, r),
            None => return found,
        }
    }
}

/// Adds the rays `early` into a child of `node` to `suspects`, traced
/// again from `node` (`from`) where they were not suspect above it.
#[inline(always)]
fn suspect_below(suspects: &mut u32, from: &mut [u32; PACKET], early: u32, node: u32) {
    let mut new = early & !*suspects;
    *suspects |= early;
    while new != 0 {
        from[new.trailing_zeros() as usize] = node;
        new &= new - 1;
    }
}

/// One ray alone: the single-ray kernel (`Kernel::visit`, the scene's
/// features compiled out) from node `from` (0: the root), its closest hit
/// (with `any_hit`, its first) along the ray as given and its block.
#[inline(always)]
fn trace_alone(
    kernel: &f32::Kernel,
    ray: &layout::Ray,
    any_hit: bool,
    from: u32,
) -> (f32::Hit, u32) {
    let (ray, shear) = f32::prepare_ray(f32::Ray::from_query(ray));
    let mut traversal = f32::Traversal::new(ray, shear, any_hit).below(from);
    let mut stack = f32::new_stack();
    // SAFETY: one stack for the whole traversal; no VECTOR_SORT.
    while unsafe { kernel.visit::<false, false, 0>(&mut traversal, &mut stack) } {}
    (traversal.answer(), traversal.hit_block)
}

/// Traces `rays` (one chunk of a query), handing `out` each ray's index,
/// closest hit (with `any_hit`, its first hit: `Kernel::visit`'s) along
/// the ray as given, and the block that holds it,
/// `PACKET` at a time (a packet of mixed octants, or with a NaN, and the
/// last few rays ray by ray); the hits the single-ray kernel's, bit for
/// bit. The scene must be triangles alone under the watertight test
/// (`Kernel::features` 0), traversing its BVH. With `ymm` (the CPU has
/// AVX2 and FMA: `CpuKernel::ymm_boxes`), node visits in 8-lane registers.
#[inline(always)]
pub(super) fn trace_packets(
    kernel: &f32::Kernel,
    rays: &[layout::Ray],
    ymm: bool,
    any_hit: bool,
    mut out: impl FnMut(usize, f32::Hit, u32),
) {
    let mut p = Packet::new();
    let mut start = 0;
    while start < rays.len() {
        let group = &rays[start..(start + PACKET).min(rays.len())];
        let packed = match <&[layout::Ray; PACKET]>::try_from(group) {
            // SAFETY: `ymm` says the CPU has AVX2.
            #[cfg(target_arch = "x86_64")]
            Ok(group) if ymm => unsafe { p.load_ymm(group) },
            Ok(group) => p.load(&group.map(|ray| f32::Ray::from_query(&ray))),
            Err(_) => false,
        };
        if !packed {
            for (i, ray) in group.iter().enumerate() {
                let (hit, block) = trace_alone(kernel, ray, any_hit, 0);
                out(start + i, hit, block);
            }
            start += group.len();
            continue;
        }
        let found = if any_hit {
            trace_packet::<true>(kernel, &mut p, ymm)
        } else {
            trace_packet::<false>(kernel, &mut p, ymm)
        };
        for (r, ray) in group.iter().enumerate() {
            let (hit, block) = if found.again >> r & 1 != 0 {
                trace_alone(kernel, ray, any_hit, found.from[r])
            } else {
                (f32::unscale(found.hits[r], &p.shears[r]), found.blocks[r])
            };
            out(start + r, hit, block);
        }
        start += PACKET;
    }
}

/// Row `y` of the render's pixels (`width` of them, `spp` samples each),
/// `PACKET` pixels at a time: each sample's camera rays of the packet's
/// pixels traced together (`Kernel::trace_closest` for a packet it cannot
/// trace, and for a ray to trace again), then each pixel's radiance added
/// in sample order, as `Kernel::add_samples` adds them; `out` takes each
/// pixel's x and `Kernel::render_pixel`'s answer, bit for bit. The scene
/// must be triangles alone under the watertight test (`Kernel::features`
/// 0), traversing its BVH (not the GPU's compressed nodes).
#[inline(always)]
pub(super) fn render_row(
    kernel: &f32::Kernel,
    y: u32,
    width: usize,
    spp: u32,
    ymm: bool,
    mut out: impl FnMut(usize, (f32::Vec3, u32, f32::Real)),
) {
    let mut p = Packet::new();
    for start in (0..width).step_by(PACKET) {
        let n = PACKET.min(width - start);
        // A short last packet repeats its last pixel; only n are kept.
        let x = |i: usize| (start + i.min(n - 1)) as u32;
        let mut sums = [(f32::Vec3::ZERO, 0.0); PACKET];
        let mut first = [NO_HIT; PACKET];
        for sample in 0..spp {
            let rays: [f32::Ray; PACKET] = std::array::from_fn(|i| {
                let (px, py) = kernel.sample_position(x(i), y, sample);
                kernel.camera_ray(px, py)
            });
            let mut hits = [f32::miss(); PACKET];
            if p.load(&rays) {
                let found = trace_packet::<false>(kernel, &mut p, ymm);
                for (r, hit) in hits.iter_mut().enumerate() {
                    *hit = if found.again >> r & 1 != 0 {
                        kernel.trace_closest(rays[r])
                    } else {
                        f32::unscale(found.hits[r], &p.shears[r])
                    };
                }
            } else {
                for (hit, &ray) in hits.iter_mut().zip(&rays) {
                    *hit = kernel.trace_closest(ray);
                }
            }
            for i in 0..n {
                if sample == 0 {
                    first[i] = hits[i].prim;
                }
                let radiance = kernel.radiance(&rays[i], &hits[i], x(i), y, sample);
                sums[i] = kernel.add_sample(sums[i], radiance);
            }
        }
        for i in 0..n {
            let (mean, variance) = kernel.pixel_mean(sums[i]);
            out(start + i, (mean, first[i], variance));
        }
    }
}
