//! Bounding volume hierarchy over all primitives (triangles and spheres),
//! built with a binned surface-area heuristic and flattened into the node
//! layout the shader traverses.
//!
//! Node layout (`layout::BvhNode`, 32 bytes): `min`, `first`, `max`, `count`.
//! A leaf has `count > 0` and owns `prims[first .. first + count]` (primitive
//! ids). An interior node has `count == 0`; its children are the adjacent
//! nodes `first` and `first + 1`. Node 0 is the root. The tree is at most
//! `MAX_DEPTH` deep, so traversal fits the shader's fixed stack.

use glam::Vec3;
use rayon::prelude::*;

use crate::layout::{BvhNode, Sphere, Triangle};

/// Deepest level the builder creates; the shader's stack holds this many
/// entries (`STACK_SIZE` in trace.wgsl).
pub const MAX_DEPTH: usize = 64;
const BINS: usize = 16;
/// Primitives per leaf above which a leaf is never made (unless the
/// primitives cannot be told apart by position).
const MAX_LEAF: usize = 8;
/// SAH costs of a node visit and of a primitive test.
const COST_TRAVERSAL: f32 = 1.0;
const COST_INTERSECT: f32 = 1.0;
/// Subtrees above this size are built in parallel.
const PARALLEL_THRESHOLD: usize = 4096;

#[derive(Clone, Debug, Default)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    /// Primitive ids in leaf order.
    pub prims: Vec<u32>,
    pub build_time: std::time::Duration,
}

#[derive(Clone, Copy, Debug)]
struct Aabb {
    min: Vec3,
    max: Vec3,
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    fn grow(&mut self, other: &Aabb) {
        self.min = self.min.min(other.min);
        self.max = self.max.max(other.max);
    }

    fn grow_point(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    fn half_area(&self) -> f32 {
        let d = (self.max - self.min).max(Vec3::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }

    fn centre(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }
}

/// The tree before flattening.
enum BuildNode {
    Leaf {
        bounds: Aabb,
        prims: Vec<u32>,
    },
    Interior {
        bounds: Aabb,
        children: Box<[BuildNode; 2]>,
    },
}

impl BuildNode {
    fn bounds(&self) -> Aabb {
        match self {
            BuildNode::Leaf { bounds, .. } | BuildNode::Interior { bounds, .. } => *bounds,
        }
    }
}

/// Per-primitive bounds and centroid.
struct Item {
    prim: u32,
    bounds: Aabb,
    centre: Vec3,
}

impl Bvh {
    pub fn build(triangles: &[Triangle], spheres: &[Sphere]) -> Bvh {
        let start = std::time::Instant::now();
        let triangle_items = triangles.par_iter().enumerate().map(|(i, t)| {
            let mut b = Aabb::EMPTY;
            for v in [t.v0, t.v1, t.v2] {
                b.grow_point(Vec3::from(v));
            }
            (i as u32, b)
        });
        let offset = triangles.len() as u32;
        let sphere_items = spheres.par_iter().enumerate().map(|(i, s)| {
            let c = Vec3::from(s.center);
            let r = Vec3::splat(s.radius);
            (
                offset + i as u32,
                Aabb {
                    min: c - r,
                    max: c + r,
                },
            )
        });
        let items: Vec<Item> = triangle_items
            .chain(sphere_items)
            .map(|(prim, bounds)| Item {
                prim,
                bounds,
                centre: bounds.centre(),
            })
            .collect();
        if items.is_empty() {
            return Bvh::default();
        }
        let root = build_node(items, 0);
        let mut bvh = Bvh::default();
        bvh.nodes.push(BvhNode::default());
        bvh.flatten(root, 0);
        bvh.build_time = start.elapsed();
        bvh
    }

    fn flatten(&mut self, node: BuildNode, index: usize) {
        let bounds = node.bounds();
        let (first, count) = match node {
            BuildNode::Leaf { prims, .. } => {
                let first = self.prims.len() as u32;
                self.prims.extend_from_slice(&prims);
                (first, prims.len() as u32)
            }
            BuildNode::Interior { children, .. } => {
                let first = self.nodes.len();
                self.nodes.push(BvhNode::default());
                self.nodes.push(BvhNode::default());
                let [left, right] = *children;
                self.flatten(left, first);
                self.flatten(right, first + 1);
                (first as u32, 0)
            }
        };
        self.nodes[index] = BvhNode {
            min: bounds.min.to_array(),
            first,
            max: bounds.max.to_array(),
            count,
        };
    }

    /// Expected cost of a random ray by the SAH (traversal and intersection
    /// costs of 1), relative to the root's area: lower is better.
    pub fn sah_cost(&self) -> f64 {
        let Some(root) = self.nodes.first() else {
            return 0.0;
        };
        let area = |n: &BvhNode| {
            Aabb {
                min: Vec3::from(n.min),
                max: Vec3::from(n.max),
            }
            .half_area() as f64
        };
        let root_area = area(root).max(f64::MIN_POSITIVE);
        self.nodes
            .iter()
            .map(|n| {
                let cost = if n.count > 0 {
                    COST_INTERSECT as f64 * n.count as f64
                } else {
                    COST_TRAVERSAL as f64
                };
                cost * area(n) / root_area
            })
            .sum()
    }

    /// Levels below the root of the deepest leaf.
    pub fn depth(&self) -> usize {
        fn depth_of(bvh: &Bvh, index: usize) -> usize {
            let n = &bvh.nodes[index];
            if n.count > 0 {
                0
            } else {
                1 + depth_of(bvh, n.first as usize).max(depth_of(bvh, n.first as usize + 1))
            }
        }
        if self.nodes.is_empty() {
            0
        } else {
            depth_of(self, 0)
        }
    }

    /// Bytes on the device: nodes plus the primitive index list.
    pub fn device_bytes(&self) -> usize {
        std::mem::size_of_val(self.nodes.as_slice()) + std::mem::size_of_val(self.prims.as_slice())
    }
}

fn bounds_of(items: &[Item]) -> (Aabb, Aabb) {
    let mut bounds = Aabb::EMPTY;
    let mut centres = Aabb::EMPTY;
    for item in items {
        bounds.grow(&item.bounds);
        centres.grow_point(item.centre);
    }
    (bounds, centres)
}

fn leaf(bounds: Aabb, items: &[Item]) -> BuildNode {
    BuildNode::Leaf {
        bounds,
        prims: items.iter().map(|i| i.prim).collect(),
    }
}

fn build_node(mut items: Vec<Item>, depth: usize) -> BuildNode {
    let (bounds, centres) = bounds_of(&items);
    let n = items.len();
    if n == 1 || depth + 1 >= MAX_DEPTH {
        return leaf(bounds, &items);
    }
    let extent = centres.max - centres.min;
    let split = if extent.max_element() > 0.0 {
        best_binned_split(&items, &centres, bounds.half_area())
    } else {
        None
    };
    let right = match split {
        Some((axis, bin, cost)) => {
            if cost >= COST_INTERSECT * n as f32 && n <= MAX_LEAF {
                return leaf(bounds, &items);
            }
            let scale = BINS as f32 / extent[axis];
            let min = centres.min[axis];
            let (left, right): (Vec<Item>, Vec<Item>) = items
                .into_iter()
                .partition(|it| bin_of(it.centre[axis], min, scale) < bin);
            items = left;
            right
        }
        // Centres coincide (or no split separates them): halve by order, so
        // even identical primitives give a balanced tree.
        None => {
            if n <= MAX_LEAF {
                return leaf(bounds, &items);
            }
            items.split_off(n / 2)
        }
    };
    let (left, right) = if n > PARALLEL_THRESHOLD {
        rayon::join(
            || build_node(items, depth + 1),
            || build_node(right, depth + 1),
        )
    } else {
        (build_node(items, depth + 1), build_node(right, depth + 1))
    };
    BuildNode::Interior {
        bounds,
        children: Box::new([left, right]),
    }
}

fn bin_of(x: f32, min: f32, scale: f32) -> usize {
    (((x - min) * scale) as usize).min(BINS - 1)
}

/// (axis, first bin of the right side, SAH cost) of the cheapest split.
fn best_binned_split(items: &[Item], centres: &Aabb, area: f32) -> Option<(usize, usize, f32)> {
    let mut best: Option<(usize, usize, f32)> = None;
    for axis in 0..3 {
        let extent = centres.max[axis] - centres.min[axis];
        if extent <= 0.0 {
            continue;
        }
        let scale = BINS as f32 / extent;
        let mut bins = [(Aabb::EMPTY, 0usize); BINS];
        for it in items {
            let b = &mut bins[bin_of(it.centre[axis], centres.min[axis], scale)];
            b.0.grow(&it.bounds);
            b.1 += 1;
        }
        // Sweep from the right, then from the left.
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0usize; BINS];
        let mut acc = Aabb::EMPTY;
        let mut count = 0;
        for i in (1..BINS).rev() {
            acc.grow(&bins[i].0);
            count += bins[i].1;
            right_area[i] = acc.half_area();
            right_count[i] = count;
        }
        let mut acc = Aabb::EMPTY;
        let mut count = 0;
        for i in 1..BINS {
            acc.grow(&bins[i - 1].0);
            count += bins[i - 1].1;
            if count == 0 || right_count[i] == 0 {
                continue;
            }
            let cost = COST_TRAVERSAL
                + COST_INTERSECT
                    * (acc.half_area() * count as f32 + right_area[i] * right_count[i] as f32)
                    / area.max(f32::MIN_POSITIVE);
            if best.is_none_or(|b| cost < b.2) {
                best = Some((axis, i, cost));
            }
        }
    }
    best
}
