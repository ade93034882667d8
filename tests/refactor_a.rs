//! Issue 45, item 2: the CPU twin written once for both precisions, so that
//! the f64 oracle is f64 end to end: its closest points, its texture
//! coordinates and its winding numbers too, not f32 code called with
//! rounded arguments.

mod common;

use glam::DVec3;
use lambert::bvh::WindingTree;
use lambert::cpu;
use lambert::layout::{FLAG_ATTRIBUTES, Triangle, TriangleAttributes};
use lambert::loading::material::{Filter, IDENTITY_UV_TRANSFORM, Sampler, TextureUse, Wrap};
use lambert::texture::{DecodedImage, TextureStore};

use common::data::tri;

/// A query point a millimetre above a unit triangle 10 km from the origin,
/// off its corners by less than f32 resolves there (a millimetre): the
/// oracle finds the nearest point and distance to f64's precision.
#[test]
fn the_oracles_closest_points_are_f64() {
    let scene = common::scene_of(
        vec![tri(
            [10000.0, 10000.0, 0.0],
            [10001.0, 10000.0, 0.0],
            [10000.0, 10001.0, 0.0],
        )],
        vec![],
    );
    let p = DVec3::new(10000.25 + 1e-7, 10000.25 - 3e-7, 1e-3);
    let mut queue = cpu::f64::BoxQueue::new();
    let margin = cpu::f64::query_margin(p.abs().max_element(), 2e4);
    let nearest = cpu::f64::closest_point(
        scene.bvh(),
        1,
        p,
        f64::INFINITY,
        margin,
        None,
        &mut queue,
        true,
    )
    .expect("the triangle is found");
    assert_eq!(nearest.prim, 0);
    assert!(
        (nearest.d2 - 1e-6).abs() < 1e-15,
        "squared distance {} (1e-6 exactly)",
        nearest.d2
    );
    let error = (nearest.point - DVec3::new(p.x, p.y, 0.0))
        .abs()
        .max_element();
    assert!(
        error < 1e-10,
        "nearest point {:?}, off by {error}",
        nearest.point
    );
    assert!((nearest.u - (0.25 + 1e-7)).abs() < 1e-10, "u {}", nearest.u);
    assert!((nearest.v - (0.25 - 3e-7)).abs() < 1e-10, "v {}", nearest.v);
}

/// A closed tetrahedron facing outward: the oracle's winding number is 1
/// inside and 0 outside to f64's precision (its solid angles are f64's,
/// arctangent included), where f32's are right to about 1e-7.
#[test]
fn the_oracles_winding_numbers_are_f64() {
    let [a, b, c, d] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let scene = common::scene_of(
        vec![tri(a, c, b), tri(a, b, d), tri(a, d, c), tri(b, c, d)],
        vec![],
    );
    let tree = WindingTree::build(scene.bvh(), scene.triangles().len());
    for (q, expected) in [
        (DVec3::new(0.2, 0.3, 0.1), 1.0),
        (DVec3::new(0.01, 0.02, 0.03), 1.0),
        (DVec3::new(0.5, 0.5, 0.5), 0.0),
        (DVec3::new(-0.3, 0.2, 0.4), 0.0),
    ] {
        let w = cpu::f64::winding_number(&tree, scene.triangles(), q);
        assert!(
            (w - expected).abs() < 1e-13,
            "winding number {w} at {q} ({expected} exactly)"
        );
    }
}

/// A texture of two texels, white then black, read nearest, on a triangle
/// whose texture coordinates are its barycentrics: at u = 0.5 − 1e-9 the
/// oracle reads the white texel, as f64 has it left of the boundary (f32
/// rounds u to 0.5 and reads the black one).
#[test]
fn the_oracles_texture_coordinates_are_f64() {
    let mut scene = common::scene_of(
        vec![Triangle {
            flags: FLAG_ATTRIBUTES,
            ..tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
        }],
        vec![],
    );
    let mut store = TextureStore::default();
    let image = DecodedImage {
        width: 2,
        height: 1,
        rgba: [[255, 255, 255, 255], [0, 0, 0, 255]].concat(),
        format: "PNG",
    };
    let index = store.add_image(&image, "test".into());
    let sampler = Sampler {
        wrap_u: Wrap::ClampToEdge,
        wrap_v: Wrap::ClampToEdge,
        magnify: Filter::Nearest,
        minify: Filter::Nearest,
        mipmaps: false,
    };
    let slot = store.slot(
        index,
        &TextureUse {
            image: 0,
            sampler,
            transform: IDENTITY_UV_TRANSFORM,
        },
    );
    *scene.textures_mut() = store;
    let material = scene.triangles()[0].material as usize;
    scene.materials_mut()[material].base_color = [1.0; 4];
    scene.materials_mut()[material].base_color_texture = slot;
    *scene.attributes_mut() = vec![TriangleAttributes {
        uvs: [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
        ..Default::default()
    }];
    let kernel = cpu::f64::Kernel::new(&scene);
    let tri = scene.triangles()[0];
    let color = |u: f64| kernel.base_color_at(&tri, 0, u, 0.25, DVec3::Z, 0.0).x;
    assert!(color(0.5 - 1e-9) > 0.99, "white left of the boundary");
    assert!(color(0.5 + 1e-9) < 0.01, "black right of it");
    // The same coordinate through the f32 twin rounds to the boundary.
    let kernel32 = cpu::f32::Kernel::new(&scene);
    let red32 = kernel32.base_color_at(&tri, 0, (0.5 - 1e-9) as f32, 0.25, glam::Vec3::Z, 0.0);
    assert!(red32.x < 0.01, "f32 reads the black texel");
}
