//! The emitters' table and light sampling (docs/rendering.md, "Lights"):
//! the alias table's probabilities are the emitters' shares of power (as
//! pbrt-v4's PowerLightSampler weighs them), picks follow them, a
//! triangle's sample has the pdf `emitter_pdf` gives the ray that hits
//! it, the irradiance estimated from samples is Lambert's of the polygon,
//! punctual lights give π·color, spots fall off, textured emitters read
//! their texture, and an edit rebuilds the table.

mod common;

use std::f64::consts::PI;

use glam::{DVec3, Vec2, Vec3};
use lambert::Scene;
use lambert::cpu::f32::{Kernel, Ray};
use lambert::layout::{
    EMITTER_ENVIRONMENT, EMITTER_LIGHT, EMITTER_TRIANGLE, FLAG_ATTRIBUTES, TriangleAttributes,
};
use lambert::loading::material::{Filter, IDENTITY_UV_TRANSFORM, Sampler, TextureUse, Wrap};
use lambert::probe::Rng;
use lambert::texture::DecodedImage;

use common::lights::{
    color_spec, directional_light, floor, floor_with_quad, point_light, spot_light, unit_f32,
};

fn mean(c: [f32; 3]) -> f64 {
    c.iter().map(|&v| v as f64).sum::<f64>() / 3.0
}

/// Each entry's probability as its alias table's bins give it: its own
/// bin's q, and the rest of every bin whose alias it is, over n.
fn bin_probabilities(scene: &Scene) -> Vec<f64> {
    let entries = &scene.emitters().entries;
    let n = entries.len() as f64;
    let mut p = vec![0.0; entries.len()];
    for (i, e) in entries.iter().enumerate() {
        p[i] += e.q as f64 / n;
        p[e.alias_bin as usize] += (1.0 - e.q as f64) / n;
    }
    p
}

/// Every emitter, its power as pbrt-v4 reckons it (the path integrator's
/// punctual lights emitting π·color): two-sided triangles 2π·A·L, a point
/// light 4π·I, a spot 2π·I·((1 − cos inner) + (cos inner − cos outer)/3)
/// for its t² falloff, a directional light and the environment what
/// crosses the disc of the scene's bounding sphere.
#[test]
fn the_table_weighs_emitters_by_power() {
    let mut scene = floor_with_quad([1.0, 2.0, 3.0]);
    let (point, spot, sun) = ([3.0, 2.0, 1.0], [0.5, 0.5, 5.0], [0.2, 0.3, 0.4]);
    scene.lights_mut().push(point_light([0.0, 3.0, 0.0], point));
    scene.lights_mut().push(spot_light(
        [1.0, 3.0, 0.0],
        [0.0, -1.0, 0.0],
        spot,
        20.0,
        30.0,
    ));
    scene
        .lights_mut()
        .push(directional_light([0.0, 1.0, 0.0], sun));
    scene
        .set_environment(Some(&color_spec([0.1, 0.2, 0.6], 2.0)))
        .unwrap();
    // The floor is 4 × 4 at y = 0, the quad at y = 1.
    let radius = (4.0f64 * 4.0 + 1.0 + 4.0 * 4.0).sqrt() / 2.0;
    let (ci, co) = (20f64.to_radians().cos(), 30f64.to_radians().cos());
    let expected = [
        (EMITTER_TRIANGLE, 2, 2.0 * PI * 0.25 * 2.0),
        (EMITTER_TRIANGLE, 3, 2.0 * PI * 0.25 * 2.0),
        (EMITTER_TRIANGLE, 4, 2.0 * PI * 0.02 * 4.0),
        (EMITTER_LIGHT, 0, 4.0 * PI * PI * mean(point)),
        (
            EMITTER_LIGHT,
            1,
            PI * mean(spot) * 2.0 * PI * ((1.0 - ci) + (ci - co) / 3.0),
        ),
        (EMITTER_LIGHT, 2, PI * radius * radius * PI * mean(sun)),
        (
            EMITTER_ENVIRONMENT,
            0,
            PI * radius * radius * 4.0 * PI * 2.0 * 0.3,
        ),
    ];
    let total: f64 = expected.iter().map(|e| e.2).sum();
    let table = scene.emitters();
    assert_eq!(table.entries.len(), expected.len());
    assert_eq!(table.uniform.num_emitters, 7);
    assert_eq!(table.uniform.num_triangle_emitters, 3);
    let bins = bin_probabilities(&scene);
    for ((entry, (kind, index, power)), from_bins) in table.entries.iter().zip(expected).zip(bins) {
        assert_eq!((entry.kind, entry.index), (kind, index));
        let share = power / total;
        assert!(
            (entry.pmf as f64 - share).abs() < 1e-6 * share,
            "{entry:?}: {share}"
        );
        assert!(
            (from_bins - share).abs() < 1e-6,
            "{entry:?}: bins give {from_bins}"
        );
    }
    assert_eq!(
        table.uniform.environment_pmf, table.entries[6].pmf,
        "the environment's pmf"
    );
    assert!((table.uniform.total_power as f64 - total).abs() < 1e-5 * total);
}

/// Picks over evenly spread u follow the pmfs: three point lights, told
/// apart by where their samples point.
#[test]
fn picks_follow_the_pmfs() {
    let mut scene = floor();
    let colors = [[1.0; 3], [5.0; 3], [0.5, 2.0, 0.5]];
    for (i, color) in colors.iter().enumerate() {
        scene
            .lights_mut()
            .push(point_light([i as f32 - 1.0, 1.0, 0.0], *color));
    }
    let kernel = Kernel::new(&scene);
    let n = 30_000;
    let mut counts = [0.0; 3];
    for i in 0..n {
        let u_pick = (i as f32 + 0.5) / n as f32;
        let s = kernel.sample_emitter(Vec3::ZERO, Vec3::Y, u_pick, Vec2::ZERO);
        let light = (s.wi.x / s.wi.y + 1.0).round() as usize;
        counts[light] += 1.0;
        assert_eq!(s.pdf, scene.emitters().entries[light].pmf);
    }
    let total: f64 = colors.iter().map(|&c| mean(c)).sum();
    for (count, color) in counts.iter().zip(colors) {
        let share = mean(color) / total;
        assert!(
            (count / n as f64 - share).abs() < 2.0 / n as f64,
            "{counts:?}"
        );
    }
}

/// A sample of a triangle light has the pdf `emitter_pdf` gives the ray
/// from the same point that hits it; both faces emit.
#[test]
fn a_triangle_sample_has_the_pdf_of_the_ray_that_hits_it() {
    let scene = floor_with_quad([1.0, 2.0, 3.0]);
    let kernel = Kernel::new(&scene);
    let mut rng = Rng(3);
    let mut checked = 0;
    for _ in 0..5_000 {
        let above = rng.unit() < 0.5;
        let position = Vec3::new(
            rng.range(-1.5, 1.5) as f32,
            if above { 2.0 } else { 1e-3 },
            rng.range(-1.5, 1.5) as f32,
        );
        let normal = if above { -Vec3::Y } else { Vec3::Y };
        let u = Vec2::new(unit_f32(&mut rng), unit_f32(&mut rng));
        let s = kernel.sample_emitter(position, normal, unit_f32(&mut rng), u);
        if s.pdf == 0.0 {
            continue;
        }
        assert!(!s.delta);
        let hit = kernel.trace(
            Ray {
                origin: position,
                tmin: 0.0,
                dir: s.wi,
                tmax: f32::MAX,
            },
            false,
        );
        // From above, the quad hides some of the small triangle.
        if hit.t < s.distance * (1.0 - 1e-4) {
            assert_eq!(hit.prim / 2, 1, "only the quad is in the way");
            continue;
        }
        assert!((2..=4).contains(&hit.prim), "{hit:?}");
        assert!((hit.t - s.distance).abs() < 1e-4 * s.distance);
        let pdf = kernel.emitter_pdf(position, hit.prim, s.wi, hit.t);
        assert!((pdf - s.pdf).abs() < 1e-4 * pdf, "{pdf} against {}", s.pdf);
        let l = if hit.prim == 4 {
            Vec3::splat(4.0)
        } else {
            Vec3::new(1.0, 2.0, 3.0)
        };
        assert_eq!(s.radiance, l);
        checked += 1;
    }
    assert!(checked > 4_000, "{checked}");
    // The floor and what is no triangle emit nothing.
    for prim in [0, 1, 5, u32::MAX] {
        assert_eq!(
            kernel.emitter_pdf(Vec3::Y, prim, -Vec3::Y, 1.0),
            0.0,
            "{prim}"
        );
    }
}

/// ∫ L cos θ dω over a polygon of radiance L (Lambert's formula):
/// L/2 · Σ θₖ n·ûₖ over its edges.
fn polygon_irradiance(x: DVec3, n: DVec3, corners: &[[f64; 3]], l: f64) -> f64 {
    let a: Vec<DVec3> = corners
        .iter()
        .map(|&c| (DVec3::from(c) - x).normalize())
        .collect();
    let sum: f64 = (0..a.len())
        .map(|k| {
            let (p, q) = (a[k], a[(k + 1) % a.len()]);
            p.dot(q).clamp(-1.0, 1.0).acos() * n.dot(p.cross(q).normalize())
        })
        .sum();
    (l / 2.0 * sum).abs()
}

/// The irradiance at floor points estimated from `sample_emitter`
/// (L cos/pdf, in both twins) is Lambert's, within four standard errors:
/// the pdfs' conversion to solid angle and the picks' pmfs together.
#[test]
fn sampled_irradiance_is_lamberts() {
    let scene = floor_with_quad([1.0, 1.0, 1.0]);
    let kernel = Kernel::new(&scene);
    let oracle = lambert::cpu::f64::Kernel::new(&scene);
    let quad = [
        [-0.5, 1.0, 0.0],
        [0.5, 1.0, 0.0],
        [0.5, 1.0, 0.5],
        [-0.5, 1.0, 0.5],
    ];
    let small = [[1.0, 0.5, 1.0], [1.2, 0.5, 1.0], [1.0, 0.5, 1.2]];
    for x in [DVec3::new(0.0, 0.0, 0.25), DVec3::new(1.5, 0.0, -1.0)] {
        let exact = polygon_irradiance(x, DVec3::Y, &quad, 1.0)
            + polygon_irradiance(x, DVec3::Y, &small, 4.0);
        let mut rng = Rng(17);
        let n = 200_000;
        let (mut sum, mut squares, mut sum_f64) = (0.0, 0.0, 0.0);
        for _ in 0..n {
            let (u_pick, u) = (
                unit_f32(&mut rng),
                Vec2::new(unit_f32(&mut rng), unit_f32(&mut rng)),
            );
            let s = kernel.sample_emitter(x.as_vec3(), Vec3::Y, u_pick, u);
            if s.pdf > 0.0 {
                let e = (s.radiance.x * s.wi.y / s.pdf) as f64;
                sum += e;
                squares += e * e;
            }
            let t = oracle.sample_emitter(
                x,
                DVec3::Y,
                u_pick as f64,
                glam::DVec2::new(u.x as f64, u.y as f64),
            );
            if t.pdf > 0.0 {
                sum_f64 += t.radiance.x * t.wi.y / t.pdf;
            }
        }
        let estimate = sum / n as f64;
        let error = ((squares / n as f64 - estimate * estimate) / n as f64).sqrt();
        assert!(
            (estimate - exact).abs() < 4.0 * error,
            "{x}: {estimate} ± {error} against {exact}"
        );
        assert!((sum_f64 / n as f64 - estimate).abs() < 1e-4 * exact);
    }
}

/// Punctual lights, as the path integrator treats them: π·color/r² from a
/// point light, times a spot's falloff, π·color along a directional
/// light; pdf the pick's probability; nothing below the horizon.
#[test]
fn punctual_lights_give_pi_color() {
    let one = |light| {
        let mut scene = floor();
        scene.lights_mut().push(light);
        scene
    };
    let color = [1.0, 2.0, 4.0];
    let pi_color = Vec3::from(color) * std::f32::consts::PI;
    let scene = one(point_light([0.0, 2.0, 0.0], color));
    let kernel = Kernel::new(&scene);
    let s = kernel.sample_emitter(Vec3::ZERO, Vec3::Y, 0.3, Vec2::new(0.1, 0.9));
    assert!(s.delta);
    assert_eq!((s.pdf, s.distance, s.wi), (1.0, 2.0, Vec3::Y));
    assert_eq!(s.radiance, pi_color / 4.0);
    let below = kernel.sample_emitter(Vec3::ZERO, -Vec3::Y, 0.3, Vec2::new(0.1, 0.9));
    assert_eq!(below.pdf, 0.0);
    let scene = one(directional_light([0.6, 0.8, 0.0], color));
    let s = Kernel::new(&scene).sample_emitter(Vec3::ZERO, Vec3::Y, 0.5, Vec2::ZERO);
    assert_eq!(
        (s.wi, s.radiance, s.distance),
        (Vec3::new(0.6, 0.8, 0.0), pi_color, f32::MAX)
    );
    // A spot 1 above the floor pointing down: full within 20°, none
    // beyond 30°, t² between.
    let scene = one(spot_light(
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        color,
        20.0,
        30.0,
    ));
    let kernel = Kernel::new(&scene);
    let at = |angle: f64| {
        let x = angle.to_radians().tan() as f32;
        let s = kernel.sample_emitter(Vec3::new(x, 0.0, 0.0), Vec3::Y, 0.5, Vec2::ZERO);
        s.radiance.x / (std::f32::consts::PI / s.distance.powi(2))
    };
    assert!((at(0.0) - 1.0).abs() < 1e-6);
    assert!((at(15.0) - 1.0).abs() < 1e-5);
    let (ci, co) = (20f64.to_radians().cos(), 30f64.to_radians().cos());
    let t = (25f64.to_radians().cos() - co) / (ci - co);
    assert!((at(25.0) as f64 - t * t).abs() < 1e-4, "{}", at(25.0));
    assert_eq!(at(35.0), 0.0);
}

/// A textured emitter's power is its emission times the texture's mean
/// (the coarsest mip level); its samples' radiance is the texel's.
#[test]
fn a_textured_emitter_reads_its_texture() {
    let mut scene = floor_with_quad([2.0, 2.0, 2.0]);
    let image = DecodedImage {
        width: 2,
        height: 1,
        rgba: vec![255, 0, 0, 255, 0, 0, 255, 255],
        format: "PNG",
    };
    let store = scene.textures_mut();
    let index = store.add_image(&image, "red and blue".into());
    let nearest = Sampler {
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
            sampler: nearest,
            transform: IDENTITY_UV_TRANSFORM,
        },
    );
    scene.materials_mut()[1].emissive_texture = slot;
    // Every corner of the quad reads the red texel.
    let mut attributes = vec![TriangleAttributes::default(); scene.triangles().len()];
    for prim in [2, 3] {
        attributes[prim].uvs = [[0.25, 0.5]; 3];
        scene.triangles_mut()[prim].flags |= FLAG_ATTRIBUTES;
    }
    *scene.attributes_mut() = attributes;
    // The 1×1 level: the texels' linear mean, 8-bit sRGB again.
    let texture_mean = scene.textures().mean_color(slot);
    assert!(
        (texture_mean[0] - 0.5).abs() < 0.005 && texture_mean[1] == 0.0,
        "{texture_mean:?}"
    );
    let table = scene.emitters();
    // Quad: 2π·0.5·mean(2·(m, 0, m)); small triangle: 2π·0.02·4.
    let (quad, small) = (
        2.0 * PI * 0.5 * (4.0 * texture_mean[0] / 3.0),
        2.0 * PI * 0.02 * 4.0,
    );
    let share = quad / 2.0 / (quad + small);
    assert!(
        (table.entries[0].pmf as f64 - share).abs() < 1e-6,
        "{:?}",
        table.entries
    );
    let kernel = Kernel::new(&scene);
    let s = kernel.sample_emitter(Vec3::new(0.0, 0.0, 0.25), Vec3::Y, 0.1, Vec2::new(0.3, 0.6));
    assert_eq!(s.radiance, Vec3::new(2.0, 0.0, 0.0));
}

/// An edit of the lights, materials or geometry rebuilds the table.
#[test]
fn edits_rebuild_the_table() {
    let mut scene = floor();
    assert!(scene.emitters().entries.is_empty());
    scene
        .lights_mut()
        .push(point_light([0.0, 1.0, 0.0], [1.0; 3]));
    assert_eq!(scene.emitters().entries.len(), 1);
    scene.materials_mut()[0].emission = [1.0; 3];
    assert_eq!(scene.emitters().uniform.num_triangle_emitters, 2);
    scene
        .set_environment(Some(&color_spec([1.0; 3], 1.0)))
        .unwrap();
    assert_eq!(scene.emitters().entries.len(), 4);
    scene.set_environment(None).unwrap();
    assert_eq!(scene.emitters().entries.len(), 3);
    assert_eq!(scene.emitters().uniform.environment_pmf, 0.0);
}
