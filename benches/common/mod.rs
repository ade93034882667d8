//! Shared by `benches/bvh.rs` (criterion) and `benches/bvh_compare.rs`
//! (one-shot table): the model ladder, obvhs's BVH2 builders, and the
//! conversion of an obvhs `Bvh2` into our flattened node layout, so that our
//! own CPU traversal (`cpu::trace_rays`) traces either tree and trace speed
//! measures tree quality alone.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use glam::{Vec3, Vec3A};
use lambert::bvh::{Aabb, BinaryNode, Bvh};
use lambert::layout::{Hit, NO_HIT, Triangle};
use obvhs::BvhBuildParams;
use obvhs::bvh2::Bvh2;

/// The ladder of models (../shared/models, smallest first), or the bundled
/// dragon_res4 when the shared models are absent. `LAMBERT_BENCH_MODELS`
/// (comma-separated file stems, e.g. `dragon_res4,dragon`) restricts it.
pub fn ladder() -> Vec<(String, PathBuf)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut models = lambert::bench::default_ladder(&root.join("../shared/models"));
    if models.is_empty() {
        models.push(root.join("assets/scenes/meshes/dragon_res4.obj"));
    }
    let only: Option<Vec<String>> = std::env::var("LAMBERT_BENCH_MODELS")
        .ok()
        .map(|s| s.split(',').map(|n| n.trim().to_string()).collect());
    let models: Vec<(String, PathBuf)> = models
        .into_iter()
        .map(|p| (p.file_stem().unwrap().to_string_lossy().into_owned(), p))
        .filter(|(name, _)| only.as_ref().is_none_or(|o| o.contains(name)))
        .collect();
    assert!(
        !models.is_empty(),
        "LAMBERT_BENCH_MODELS matches no model of the ladder"
    );
    models
}

/// The largest model of the ladder (the full dragon where present).
pub fn largest() -> (String, PathBuf) {
    ladder().pop().expect("at least the bundled mesh")
}

/// The smallest model of the ladder (dragon_res4).
pub fn smallest() -> (String, PathBuf) {
    ladder().swap_remove(0)
}

/// obvhs presets compared against our builder.
pub fn presets() -> Vec<(&'static str, BvhBuildParams)> {
    vec![
        ("obvhs-very_fast", BvhBuildParams::very_fast_build()),
        ("obvhs-fast", BvhBuildParams::fast_build()),
        ("obvhs-medium", BvhBuildParams::medium_build()),
        ("obvhs-slow", BvhBuildParams::slow_build()),
        // The same presets with leaves collapsed under our SAH constants
        // (traversal = intersection = 1) instead of obvhs's traversal = 3.
        (
            "obvhs-medium-ct1",
            BvhBuildParams {
                collapse_traversal_cost: 1.0,
                ..BvhBuildParams::medium_build()
            },
        ),
        (
            "obvhs-slow-ct1",
            BvhBuildParams {
                collapse_traversal_cost: 1.0,
                ..BvhBuildParams::slow_build()
            },
        ),
        // obvhs's heaviest preset (reinsertion over all nodes), our constants.
        (
            "obvhs-very_slow-ct1",
            BvhBuildParams {
                collapse_traversal_cost: 1.0,
                ..BvhBuildParams::very_slow_build()
            },
        ),
    ]
}

/// Whether `label` is worth building on a model of `triangles`: the
/// very slow preset takes several seconds from ~1M triangles on 2 cores.
pub fn preset_fits(label: &str, triangles: usize) -> bool {
    !(label.contains("very_slow") && triangles > 300_000)
}

pub fn to_obvhs(triangles: &[Triangle]) -> Vec<obvhs::triangle::Triangle> {
    triangles
        .iter()
        .map(|t| obvhs::triangle::Triangle {
            v0: Vec3A::from(t.v0),
            v1: Vec3A::from(t.v1),
            v2: Vec3A::from(t.v2),
        })
        .collect()
}

/// Stage times of one obvhs build, converted to our layout.
#[derive(Clone, Copy, Debug, Default)]
pub struct ObvhsTimes {
    /// Our triangles to obvhs's.
    pub convert: Duration,
    /// `build_bvh2_from_tris` (PLOC, reinsertion, leaf collapse, and the
    /// spatial pre-splits of the slow preset).
    pub build: Duration,
    /// Reordering into our layout.
    pub flatten: Duration,
}

impl ObvhsTimes {
    pub fn total(&self) -> Duration {
        self.convert + self.build + self.flatten
    }
}

/// obvhs's BVH2 for `triangles` (the scene has no spheres), in our layout;
/// `build_time` is the whole pipeline (convert + build + flatten).
pub fn build_obvhs(triangles: &[Triangle], params: BvhBuildParams) -> (Bvh, ObvhsTimes) {
    let t0 = Instant::now();
    let tris = to_obvhs(triangles);
    let t1 = Instant::now();
    let bvh2 = obvhs::bvh2::builder::build_bvh2_from_tris(&tris, params, &mut Duration::default());
    let t2 = Instant::now();
    let mut bvh = flatten(&bvh2, triangles);
    let t3 = Instant::now();
    let times = ObvhsTimes {
        convert: t1 - t0,
        build: t2 - t1,
        flatten: t3 - t2,
    };
    bvh.build_time = times.total();
    (bvh, times)
}

/// Our wide layout from an obvhs `Bvh2`: its binary tree (nodes reachable
/// from the root) collapsed by `Bvh::from_binary`, exactly as our own
/// builder's tree is.
pub fn flatten(bvh2: &Bvh2, triangles: &[Triangle]) -> Bvh {
    if bvh2.nodes.is_empty() {
        return Bvh::default();
    }
    Bvh::from_binary(binary_node(bvh2, 0), triangles)
}

fn binary_node(bvh2: &Bvh2, index: usize) -> BinaryNode {
    let node = &bvh2.nodes[index];
    let aabb = node.aabb();
    let bounds = Aabb {
        min: Vec3::from(aabb.min),
        max: Vec3::from(aabb.max),
    };
    if node.is_leaf() {
        let range = node.first_index as usize..(node.first_index + node.prim_count) as usize;
        BinaryNode::Leaf {
            bounds,
            prims: bvh2.primitive_indices[range].to_vec(),
        }
    } else {
        let first = node.first_index as usize;
        BinaryNode::Interior {
            bounds,
            children: Box::new([binary_node(bvh2, first), binary_node(bvh2, first + 1)]),
        }
    }
}

/// How `hits` agree with `reference`, ray by ray.
#[derive(Clone, Copy, Debug, Default)]
pub struct HitAgreement {
    pub rays: usize,
    /// Same primitive (or both miss).
    pub same_prim: usize,
    /// Different primitive at the same distance (rel. 1e-5): a tie on a
    /// shared edge or vertex, found in another order.
    pub tie: usize,
    /// Anything else: a real disagreement.
    pub differ: usize,
}

pub fn agreement(reference: &[Hit], hits: &[Hit]) -> HitAgreement {
    assert_eq!(reference.len(), hits.len());
    let mut a = HitAgreement {
        rays: hits.len(),
        ..Default::default()
    };
    for (r, h) in reference.iter().zip(hits) {
        if r.prim == h.prim {
            a.same_prim += 1;
        } else if r.prim != NO_HIT
            && h.prim != NO_HIT
            && (r.t - h.t).abs() <= 1e-5 * r.t.abs().max(1e-6)
        {
            a.tie += 1;
        } else {
            a.differ += 1;
        }
    }
    a
}

/// Leaves, and primitive references in leaves (> triangles with pre-splits).
pub fn leaf_stats(bvh: &Bvh) -> (usize, usize) {
    let refs = bvh
        .blocks
        .iter()
        .flat_map(|b| b.prims)
        .filter(|&p| p != NO_HIT);
    (bvh.leaf_count(), refs.count())
}
