//! The winding tree: per-node dipoles over the wide BVH's hierarchy for
//! fast generalized winding numbers (Barill, Dickson, Schmidt, Levin and
//! Jacobson, "Fast Winding Numbers for Soups and Clouds", SIGGRAPH 2018).
//! Built from the BVH alone (its leaf blocks hold the vertices), on the
//! first winding query, and kept with the BVH (`Bvh::winding_tree`), so
//! that renders pay nothing for it. One flat array both paths walk in the
//! same order (`shaders/winding.wgsl` and `cpu/winding.rs`), so their sums
//! agree bit for bit.

use glam::DVec3;

use super::{Bvh, occupied_slots};
use crate::layout::{LEAF_BIT, WindingNode, leaf_range};

/// The winding tree of a BVH: node 0 is the root; each node's interior
/// children are consecutive (breadth first), its leaves' triangles listed
/// in `prims`.
#[derive(Clone, Debug, Default)]
pub struct WindingTree {
    pub nodes: Vec<WindingNode>,
    pub prims: Vec<u32>,
}

/// A subtree's dipole while it is built, in f64.
#[derive(Clone, Copy, Default)]
struct Dipole {
    normal: DVec3,
    /// Σ area · centroid, and Σ area.
    weighted: DVec3,
    area: f64,
    /// Σ centroid and how many, for a subtree of zero area.
    centroids: DVec3,
    count: f64,
}

impl Dipole {
    fn add(&mut self, other: &Dipole) {
        self.normal += other.normal;
        self.weighted += other.weighted;
        self.area += other.area;
        self.centroids += other.centroids;
        self.count += other.count;
    }

    fn centre(&self) -> DVec3 {
        if self.area > 0.0 {
            self.weighted / self.area
        } else if self.count > 0.0 {
            self.centroids / self.count
        } else {
            DVec3::ZERO
        }
    }
}

impl WindingTree {
    /// The tree of `bvh`, whose primitives below `triangle_count` are
    /// triangles (spheres, above, are left out).
    pub fn build(bvh: &Bvh, triangle_count: usize) -> WindingTree {
        // Breadth first: order[new] = the wide node it comes from.
        let mut order = vec![0usize];
        let mut first_child = Vec::new();
        let mut head = 0;
        while head < order.len() {
            first_child.push(order.len() as u32);
            let node = &bvh.nodes[order[head]];
            for slot in occupied_slots(node) {
                let child = node.children[slot];
                if child & LEAF_BIT == 0 {
                    order.push(child as usize);
                }
            }
            head += 1;
        }
        let mut tree = WindingTree {
            nodes: vec![WindingNode::default(); order.len()],
            prims: Vec::new(),
        };
        let mut vertices: Vec<Vec<[[f32; 3]; 3]>> = vec![Vec::new(); order.len()];
        for (new, &old) in order.iter().enumerate() {
            let node = &bvh.nodes[old];
            let first = tree.prims.len() as u32;
            for slot in occupied_slots(node) {
                let child = node.children[slot];
                if child & LEAF_BIT == 0 {
                    continue;
                }
                let (block, count) = leaf_range(child);
                for b in &bvh.blocks[block as usize..(block + count) as usize] {
                    for lane in 0..4 {
                        let prim = b.prims[lane];
                        if (prim as usize) < triangle_count {
                            tree.prims.push(prim);
                            vertices[new].push(std::array::from_fn(|k| {
                                std::array::from_fn(|a| b.v[k][a][lane])
                            }));
                        }
                    }
                }
            }
            tree.nodes[new] = WindingNode {
                first_child: first_child[new],
                first_prim: first,
                prim_count: tree.prims.len() as u32 - first,
                ..WindingNode::default()
            };
        }
        // Child counts from the breadth-first order itself: node i's
        // children run up to node i + 1's first child.
        for i in 0..tree.nodes.len() {
            let end = first_child
                .get(i + 1)
                .copied()
                .unwrap_or(tree.nodes.len() as u32);
            tree.nodes[i].child_count = end - tree.nodes[i].first_child;
        }
        // Dipoles and radii bottom up (children come after their parent).
        let mut dipoles = vec![Dipole::default(); tree.nodes.len()];
        let mut radii = vec![0.0f64; tree.nodes.len()];
        let mut centres = vec![DVec3::ZERO; tree.nodes.len()];
        for i in (0..tree.nodes.len()).rev() {
            let mut dipole = Dipole::default();
            for t in &vertices[i] {
                let [a, b, c] = t.map(|v| DVec3::from(v.map(f64::from)));
                let normal = 0.5 * (b - a).cross(c - a);
                let area = normal.length();
                let centroid = (a + b + c) / 3.0;
                dipole.add(&Dipole {
                    normal,
                    weighted: area * centroid,
                    area,
                    centroids: centroid,
                    count: 1.0,
                });
            }
            let node = tree.nodes[i];
            let children =
                node.first_child as usize..(node.first_child + node.child_count) as usize;
            for c in children.clone() {
                dipole.add(&dipoles[c]);
            }
            let centre = dipole.centre();
            let mut radius: f64 = 0.0;
            for t in &vertices[i] {
                for v in t {
                    radius = radius.max((DVec3::from(v.map(f64::from)) - centre).length());
                }
            }
            for c in children {
                radius = radius.max((centres[c] - centre).length() + radii[c]);
            }
            dipoles[i] = dipole;
            radii[i] = radius;
            centres[i] = centre;
            // About the centre in f32, rounded up: the ball still holds
            // every vertex.
            let centre32 = centre.as_vec3();
            let shift = (centre32.as_dvec3() - centre).length();
            tree.nodes[i].centre = centre32.to_array();
            tree.nodes[i].radius = ((radius + shift) * (1.0 + 1e-6)) as f32;
            tree.nodes[i].normal = dipole.normal.as_vec3().to_array();
        }
        tree
    }
}
