//! Closed-form answers (not the renderer's own formulas) on the GPU and CPU paths.

mod common;

use common::*;
use lambert::layout::NO_HIT;
use lambert::output::Rendered;

/// Both paths' renders of a scene.
fn both(scene: &lambert::Scene) -> [(&'static str, Rendered); 2] {
    [("GPU", render_gpu(scene)), ("CPU", render_cpu(scene))]
}

/// A large square in the plane z = 0 (normal +z), seen head-on from +z at
/// distance 3, lit by `lights`.
fn plane_scene(albedo: [f64; 3], lights: &str) -> lambert::Scene {
    scene(&format!(
        r#"
        [camera]
        eye = [0.0, 0.0, 3.0]
        look_at = [0.0, 0.0, 0.0]
        vfov = 30.0
        width = 33
        height = 33
        [[mesh]]
        obj = "meshes/quad.obj"
        albedo = {albedo:?}
        scale = 100.0
        rotate_deg = [90.0, 0.0, 0.0]
        {lights}
        "#
    ))
}

fn centre(r: &Rendered) -> [f32; 3] {
    r.image.pixel(r.image.width / 2, r.image.height / 2)
}

#[test]
fn directional_light_head_on_gives_k_times_e() {
    let k = [0.8, 0.5, 0.25];
    let e = [1.5, 2.0, 0.5];
    let s = plane_scene(
        k,
        &format!("[[directional_light]]\ndirection = [0.0, 0.0, -1.0]\nirradiance = {e:?}"),
    );
    for (path, r) in both(&s) {
        // Head-on: every pixel sees the same k·E.
        for p in &r.image.rgb {
            assert_close(*p, [k[0] * e[0], k[1] * e[1], k[2] * e[2]], 1e-5, path);
        }
    }
}

#[test]
fn directional_light_at_angle_gives_k_e_cos_theta() {
    let k = [0.9, 0.9, 0.9];
    for theta_deg in [0.0f64, 30.0, 60.0, 85.0] {
        let theta = theta_deg.to_radians();
        let dir = [theta.sin(), 0.0, -theta.cos()];
        let s = plane_scene(
            k,
            &format!("[[directional_light]]\ndirection = {dir:?}\nirradiance = 2.0"),
        );
        for (path, r) in both(&s) {
            let expected = 0.9 * 2.0 * theta.cos();
            assert_close(
                centre(&r),
                [expected; 3],
                1e-5,
                &format!("{path} θ = {theta_deg}°"),
            );
        }
    }
    // Light from behind the plane: the camera's side is unlit.
    let s = plane_scene(
        k,
        "[[directional_light]]\ndirection = [0.0, 0.0, 1.0]\nirradiance = 2.0",
    );
    for (path, r) in both(&s) {
        assert_eq!(centre(&r), [0.0; 3], "{path}: lit from behind");
    }
}

#[test]
fn point_light_head_on_gives_k_i_over_r_squared() {
    for r_dist in [0.5f64, 2.0, 7.0] {
        let s = plane_scene(
            [0.6, 0.7, 0.8],
            &format!(
                "[[point_light]]\nposition = [0.0, 0.0, {r_dist}]\nintensity = [10.0, 20.0, 30.0]"
            ),
        );
        for (path, r) in both(&s) {
            let e = 1.0 / (r_dist * r_dist);
            assert_close(
                centre(&r),
                [0.6 * 10.0 * e, 0.7 * 20.0 * e, 0.8 * 30.0 * e],
                1e-5,
                &format!("{path} r = {r_dist}"),
            );
        }
    }
}

#[test]
fn yellow_under_red_light_looks_red_and_no_light_is_black() {
    let s = plane_scene(
        [1.0, 1.0, 0.0],
        "[[directional_light]]\ndirection = [0.0, 0.0, -1.0]\nirradiance = [1.0, 0.0, 0.0]",
    );
    for (path, r) in both(&s) {
        assert_eq!(centre(&r), [1.0, 0.0, 0.0], "{path}: yellow under red");
    }
    let s = plane_scene([1.0, 1.0, 0.0], "");
    for (path, r) in both(&s) {
        assert!(
            r.image.rgb.iter().all(|p| *p == [0.0; 3]),
            "{path}: no light is black"
        );
    }
}

#[test]
fn misses_get_the_background_and_ambient_adds_k_times_a() {
    let s = scene(
        r#"
        [camera]
        eye = [0.0, 0.0, 3.0]
        look_at = [0.0, 0.0, 0.0]
        vfov = 60.0
        width = 31
        height = 31
        [render]
        background = [0.1, 0.2, 0.3]
        ambient = [0.5, 0.5, 0.5]
        [[sphere]]
        center = [0.0, 0.0, 0.0]
        radius = 0.5
        albedo = [0.4, 0.6, 0.8]
        "#,
    );
    for (path, r) in both(&s) {
        assert_eq!(r.image.pixel(0, 0), [0.1, 0.2, 0.3], "{path}: background");
        assert_eq!(r.prims[0], NO_HIT);
        assert_close(
            centre(&r),
            [0.2, 0.3, 0.4],
            1e-6,
            &format!("{path}: ambient"),
        );
    }
}

/// Projects a world point to pixel coordinates by the documented convention,
/// computed here independently in f64.
fn project(
    eye: [f64; 3],
    look_at: [f64; 3],
    up: [f64; 3],
    vfov: f64,
    w: u32,
    h: u32,
    p: [f64; 3],
) -> (f64, f64) {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let norm = |a: [f64; 3]| {
        let l = dot(a, a).sqrt();
        [a[0] / l, a[1] / l, a[2] / l]
    };
    let f = norm(sub(look_at, eye));
    let r = norm(cross(f, up));
    let u = cross(r, f);
    let d = sub(p, eye);
    let t = (vfov.to_radians() / 2.0).tan();
    let sx = dot(d, r) / dot(d, f);
    let sy = dot(d, u) / dot(d, f);
    // sx = (2(x+0.5)/W − 1)·t·W/H  and  sy = (1 − 2(y+0.5)/H)·t, for the pixel centre.
    let x = (sx / (t * w as f64 / h as f64) + 1.0) * w as f64 / 2.0;
    let y = (1.0 - sy / t) * h as f64 / 2.0;
    (x, y)
}

#[test]
fn a_known_point_lands_on_the_pixel_the_convention_predicts() {
    let (eye, look_at, up) = ([2.0, 1.5, 6.0], [0.3, 0.2, 0.0], [0.1, 1.0, 0.0]);
    let (w, h, vfov) = (97u32, 61u32, 50.0);
    for p in [[0.9, 0.7, -0.4], [-1.3, -0.2, 0.5], [0.3, 0.2, 0.0]] {
        let (x, y) = project(eye, look_at, up, vfov, w, h, p);
        // Radius: 0.8 of a pixel's footprint at that distance, so the pixel
        // centre nearest the point's image always hits the sphere.
        let distance =
            ((p[0] - eye[0]).powi(2) + (p[1] - eye[1]).powi(2) + (p[2] - eye[2]).powi(2)).sqrt();
        let radius = 0.8 * 2.0 * distance * (vfov / 2.0f64).to_radians().tan() / h as f64;
        let s = scene(&format!(
            r#"
            [camera]
            eye = {eye:?}
            look_at = {look_at:?}
            up = {up:?}
            vfov = {vfov}
            width = {w}
            height = {h}
            [[sphere]]
            center = {p:?}
            radius = {radius}
            "#
        ));
        for (path, r) in both(&s) {
            let hit: Vec<(u32, u32)> = (0..w * h)
                .filter(|i| r.prims[*i as usize] != NO_HIT)
                .map(|i| (i % w, i / w))
                .collect();
            let (px, py) = (x.floor() as u32, y.floor() as u32);
            assert!(
                hit.contains(&(px, py)),
                "{path}: point {p:?} should show at pixel ({px}, {py}) (x = {x:.3}, y = {y:.3}); hit pixels: {hit:?}"
            );
            for (hx, hy) in &hit {
                let d = ((*hx as f64 + 0.5 - x).powi(2) + (*hy as f64 + 0.5 - y).powi(2)).sqrt();
                assert!(
                    d < 1.6,
                    "{path}: pixel ({hx}, {hy}) is {d:.2} px from the point's image"
                );
            }
        }
    }
}

#[test]
fn shadows_fall_and_can_be_switched_off() {
    let base = r#"
        [camera]
        eye = [0.0, 0.0, 5.0]
        look_at = [0.0, 0.0, 0.0]
        vfov = 40.0
        width = 41
        height = 41
        [[mesh]]
        obj = "meshes/quad.obj"
        scale = 20.0
        rotate_deg = [90.0, 0.0, 0.0]
        albedo = 1.0
        [[sphere]]
        center = [0.0, 0.0, 1.0]
        radius = 0.5
        [[directional_light]]
        direction = [0.0, 0.0, -1.0]
        irradiance = 1.0
    "#;
    // A camera off to the side sees the plane point straight behind the sphere.
    let side = base.replace("eye = [0.0, 0.0, 5.0]", "eye = [3.0, 0.0, 4.0]");
    let lit = |shadows: bool| {
        let s = scene(&format!("{side}\n[render]\nshadows = {shadows}\n"));
        let target = (0.0, 0.0, 0.0);
        let (x, y) = project(
            [3.0, 0.0, 4.0],
            [0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            40.0,
            41,
            41,
            [target.0, target.1, target.2],
        );
        both(&s).map(|(path, r)| {
            (
                path,
                r.image.pixel(x as u32, y as u32),
                r.prims[(y as u32 * 41 + x as u32) as usize],
            )
        })
    };
    for (path, colour, prim) in lit(true) {
        assert!(
            prim < 2,
            "{path}: expected the plane at the shadowed point, hit {prim}"
        );
        assert_eq!(colour, [0.0; 3], "{path}: the sphere's shadow");
    }
    for (path, colour, _) in lit(false) {
        assert_close(colour, [1.0; 3], 1e-5, &format!("{path}: shadows off"));
    }
}

/// A point light lying on a visible surface (the plane z = 0, the light at
/// the origin, seen head-on): the shaded point at r = 0 gets no light from
/// it (documented), never NaN, on both paths and in the oracle; points
/// around it get the light's finite k·I·cosθ/r², which is 0 in the plane.
#[test]
fn a_point_light_on_the_surface_gives_no_nan() {
    let scene = scene(
        r#"
[camera]
eye = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
vfov = 30.0
width = 9
height = 9
[render]
ambient = [0.1, 0.1, 0.1]
[[mesh]]
obj = "meshes/quad.obj"
albedo = [0.5, 0.0, 0.5]
scale = 4.0
rotate_deg = [90.0, 0.0, 0.0]
[[point_light]]
position = [0.0, 0.0, 0.0]
intensity = 10.0
"#,
    );
    for (what, image) in [
        ("GPU", render_gpu(&scene)),
        ("CPU", render_cpu(&scene)),
        ("oracle", render_oracle(&scene)),
    ] {
        for (i, p) in image.image.rgb.iter().enumerate() {
            assert!(
                p.iter().all(|c| c.is_finite()),
                "{what}: pixel {i} is {p:?}"
            );
        }
        // The centre pixel's camera ray hits the plane at the light.
        let centre = image.image.rgb[4 * 9 + 4];
        assert_close(centre, [0.05, 0.0, 0.05], 1e-6, what);
    }
}

/// Issue 28 item 4: at the largest radius a scene may give a sphere
/// (MAX_SPHERE_RADIUS), a ray five units off its surface, head-on or
/// slanted, from outside or inside, finds the near root to 1e-5 on both
/// paths and in the oracle. The reference solves the quadratic in f64 from
/// the same f32 inputs (its own cancellation is 1e-16 of 1e12, 1e-4 of a
/// gap of 1e7).
#[test]
fn sphere_hits_are_right_at_the_radius_limit() {
    use lambert::layout::{Hit, Ray, Sphere};
    let radius = lambert::limits::MAX_SPHERE_RADIUS as f32;
    let mut rays = Vec::new();
    let mut spheres = Vec::new();
    // Centres on and off the f32 integer grid, so that o − c rounds too.
    for center in [[0.0f32, 0.0, 0.0], [123.37, -2048.61, 777.123]] {
        spheres.push(Sphere {
            center,
            radius,
            ..Default::default()
        });
        let c = glam::Vec3::from(center);
        for (axis, slant) in [
            (glam::Vec3::Z, glam::Vec3::ZERO),
            (
                glam::Vec3::new(0.6, 0.0, 0.8),
                glam::Vec3::new(0.0, 0.3, 0.0),
            ),
            (
                glam::Vec3::new(-0.48, 0.6, -0.64),
                glam::Vec3::new(0.1, 0.0, 0.05),
            ),
        ] {
            for gap in [5.0f32, -5.0, 0.75] {
                // Outside (gap > 0) the ray looks in; inside it looks out.
                let origin = c + axis * (radius + gap);
                let dir = (-axis + slant) * gap.signum();
                rays.push((
                    spheres.len() - 1,
                    Ray {
                        origin: origin.to_array(),
                        tmin: 0.0,
                        dir: dir.to_array(),
                        tmax: f32::INFINITY,
                    },
                ));
            }
        }
    }
    for (i, sphere) in spheres.iter().enumerate() {
        let scene = scene_of(vec![], vec![*sphere]);
        let mine: Vec<Ray> = rays.iter().filter(|r| r.0 == i).map(|r| r.1).collect();
        let expected: Vec<f64> = mine
            .iter()
            .map(|r| {
                let o = glam::Vec3::from(r.origin).as_dvec3();
                let d = glam::Vec3::from(r.dir).as_dvec3();
                let oc = o - glam::Vec3::from(sphere.center).as_dvec3();
                let r2 = (sphere.radius as f64).powi(2);
                let (a, b, c) = (d.dot(d), oc.dot(d), oc.dot(oc) - r2);
                let root = (b * b - a * c).sqrt();
                // The smaller positive root.
                let near = (-b - root) / a;
                if near > 0.0 { near } else { (-b + root) / a }
            })
            .collect();
        let oracle: Vec<f64> = lambert::cpu::trace_rays_f64(&scene, &mine, false)
            .iter()
            .map(|h| h.t)
            .collect();
        let as_f64 = |hits: Vec<Hit>| hits.iter().map(|h| h.t as f64).collect::<Vec<_>>();
        for (what, ts) in [
            ("oracle", oracle),
            ("CPU", as_f64(trace_cpu(&scene, &mine, false))),
            ("GPU", as_f64(trace_gpu(&scene, &mine, false))),
        ] {
            for ((t, want), ray) in ts.iter().zip(&expected).zip(&mine) {
                let error = ((t - want) / want).abs();
                println!("{what}: sphere {i}, {ray:?}: t {t} for {want} ({error:.1e})");
                assert!(
                    error <= 1e-5,
                    "{what}: sphere {i}, {ray:?}: t {t}, expected {want} (relative error {error:.1e})"
                );
            }
        }
    }
}
