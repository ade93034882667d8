//! The environment (docs/rendering.md, "The environment"): maps read from
//! .hdr and .exr files, Mitsuba 3's equirectangular convention and the
//! turn about +Y, the sampling distribution against its pdf (a chi-square
//! test), the pdf's integral, the constant environment, the `[environment]`
//! table and `--environment`, and the errors that name the file.

mod common;

use std::f64::consts::PI;
use std::path::Path;

use glam::{DVec3, Vec2, Vec3};
use lambert::Scene;
use lambert::cpu::f32::Kernel;
use lambert::lighting::MAX_ENVIRONMENT_BYTES;
use lambert::probe::Rng;

use common::lights::{
    bright_texel_map, color_spec, floor, map_spec, unit_f32, unit_vector, write_exr, write_hdr,
};

/// Mitsuba 3's direction of map coordinates (u, v) (envmap.cpp's
/// `uv_to_direction`), turned about +Y by `rotation_deg` as its
/// `to_world = rotate([0, 1, 0], angle)` turns it.
fn mitsuba_direction(u: f64, v: f64, rotation_deg: f64) -> DVec3 {
    let (theta, phi) = (PI * v, 2.0 * PI * u);
    let local = DVec3::new(
        phi.sin() * theta.sin(),
        theta.cos(),
        -phi.cos() * theta.sin(),
    );
    glam::DMat3::from_rotation_y(rotation_deg.to_radians()) * local
}

/// `floor` lit by the map at `path` alone.
fn lit_by_map(path: &Path, strength: f64, rotation_deg: f64) -> Scene {
    let mut scene = floor();
    scene
        .set_environment(Some(&map_spec(path, strength, rotation_deg)))
        .unwrap();
    scene
}

#[test]
fn hdr_and_exr_maps_read_as_written() {
    let dir = tempfile::tempdir().unwrap();
    // Values RGBE holds exactly: one exponent a pixel, 8-bit mantissas.
    let rgb = [
        [1.0, 0.5, 0.25],
        [2.0, 4.0, 1.0],
        [0.125, 0.0, 0.0625],
        [8.0, 8.0, 8.0],
        [0.5, 0.5, 0.5],
        [3.0, 1.0, 0.5],
    ];
    let hdr = dir.path().join("sky.hdr");
    let exr = dir.path().join("sky.exr");
    write_hdr(&hdr, 3, 2, &rgb);
    write_exr(
        &exr,
        3,
        2,
        &[
            [0.1, 0.2, 0.3],
            [1e4, 0.0, 7.5],
            [0.0; 3],
            [1.0; 3],
            [2.0; 3],
            [3.0; 3],
        ],
    );
    let scene = lit_by_map(&hdr, 2.0, 0.0);
    let map = scene.environment().unwrap().map.as_ref().unwrap();
    assert_eq!((map.width, map.height), (3, 2));
    let expected: Vec<[f32; 4]> = rgb
        .iter()
        .map(|c| [2.0 * c[0], 2.0 * c[1], 2.0 * c[2], 0.0])
        .collect();
    assert_eq!(map.pixels, expected);
    let scene = lit_by_map(&exr, 1.0, 0.0);
    let map = scene.environment().unwrap().map.as_ref().unwrap();
    assert_eq!(map.pixels[1], [1e4, 0.0, 7.5, 0.0]);
    assert_eq!(map.pixels[0], [0.1, 0.2, 0.3, 0.0]);
    // The map is one of the scene's inputs: no output may replace it.
    assert!(scene.inputs().contains(&exr));
    let message = scene.check_output(&exr).unwrap_err().to_string();
    assert!(message.contains("sky.exr"), "{message}");
}

/// A one-row map spans θ from 0 to π: its row is stored twice.
#[test]
fn a_one_row_map_is_its_row_at_every_height() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("band.exr");
    write_exr(&path, 2, 1, &[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let scene = lit_by_map(&path, 1.0, 0.0);
    let map = scene.environment().unwrap().map.as_ref().unwrap();
    assert_eq!((map.width, map.height), (2, 2));
    let kernel = Kernel::new(&scene);
    // Texel 0's centre, u = 1/4, is +X; at every height.
    for v in [0.05, 0.5, 0.95] {
        let d = mitsuba_direction(0.25, v, 0.0).as_vec3();
        let l = kernel.environment_radiance(d);
        assert!((l - Vec3::X).abs().max_element() < 1e-4, "{v}: {l}");
    }
}

/// One bright texel, seen where Mitsuba's convention puts it: texel (j, i)
/// of a W × H map at u = (j + ½)/W, v = i/(H − 1); u = ¼, v = ½ is +X, the
/// left edge −Z; a turn of 90° about +Y takes +X to −Z. `environment_pdf`
/// peaks there too.
#[test]
fn a_bright_texel_lights_the_direction_of_the_convention() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (8u32, 5u32);
    let path = dir.path().join("sun.exr");
    bright_texel_map(&path, w, h, (2, 1), 7);
    let bright = Vec3::new(50.0, 100.0, 150.0);
    let (u, v) = ((2.0 + 0.5) / w as f64, 1.0 / (h - 1) as f64);
    for rotation in [0.0, 90.0, -37.0] {
        let scene = lit_by_map(&path, 1.0, rotation);
        let kernel = Kernel::new(&scene);
        let d = mitsuba_direction(u, v, rotation).as_vec3();
        let l = kernel.environment_radiance(d);
        assert!(
            ((l - bright) / bright).abs().max_element() < 1e-4,
            "{rotation}°: {l}"
        );
        // The peak of the pdf over a grid of directions is beside it.
        let mut best = (0.0, Vec3::ZERO);
        for i in 0..200 {
            for j in 0..400 {
                let g = mitsuba_direction((j as f64 + 0.5) / 400.0, (i as f64 + 0.5) / 200.0, 0.0);
                let pdf = kernel.environment_pdf(g.as_vec3());
                if pdf > best.0 {
                    best = (pdf, g.as_vec3());
                }
            }
        }
        let cell = (2.0 * PI / w as f64).max(PI / (h - 1) as f64);
        let angle = (best.1.dot(d) as f64).clamp(-1.0, 1.0).acos();
        assert!(
            angle < 1.5 * cell,
            "{rotation}°: peak {} is {angle} rad from {d}",
            best.1
        );
    }
    // A turn of 90°: the map's +X seen at world −Z.
    let (turned_scene, unturned_scene) =
        (lit_by_map(&path, 1.0, 90.0), lit_by_map(&path, 1.0, 0.0));
    let turned = Kernel::new(&turned_scene).environment_radiance(-Vec3::Z);
    let unturned = Kernel::new(&unturned_scene).environment_radiance(Vec3::X);
    assert!(
        (turned - unturned).abs().max_element() < 1e-4,
        "{turned} {unturned}"
    );
}

/// ∫ environment_pdf dω over the sphere is 1 (midpoint rule in (cos θ, φ)).
fn pdf_integral(kernel: &Kernel) -> f64 {
    let (nz, nphi) = (600, 1200);
    let mut sum = 0.0;
    for i in 0..nz {
        let z = -1.0 + 2.0 * (i as f64 + 0.5) / nz as f64;
        let r = (1.0 - z * z).sqrt();
        for j in 0..nphi {
            let phi = 2.0 * PI * (j as f64 + 0.5) / nphi as f64;
            let d = DVec3::new(r * phi.cos(), z, r * phi.sin());
            sum += kernel.environment_pdf(d.as_vec3()) as f64;
        }
    }
    sum * 4.0 * PI / (nz * nphi) as f64
}

/// A floor lit by a `width` × `height` map bright at `texel` (`seed`'s
/// dim noise elsewhere), turned by `rotation_deg`; the folder holding the
/// map goes with it.
fn sun_scene(
    (width, height): (u32, u32),
    texel: (u32, u32),
    seed: u64,
    rotation_deg: f64,
) -> (tempfile::TempDir, Scene) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sun.exr");
    bright_texel_map(&path, width, height, texel, seed);
    let scene = lit_by_map(&path, 1.0, rotation_deg);
    (dir, scene)
}

#[test]
fn the_pdf_integrates_to_one() {
    let (_dir, scene) = sun_scene((16, 9), (11, 2), 3, 25.0);
    let integral = pdf_integral(&Kernel::new(&scene));
    assert!((integral - 1.0).abs() < 5e-3, "{integral}");
}

/// Wilson and Hilferty's z of a chi-square statistic with `dof` degrees of
/// freedom: about normal when the counts follow the expectations.
fn chi_square_z(statistic: f64, dof: f64) -> f64 {
    let a = 2.0 / (9.0 * dof);
    ((statistic / dof).powf(1.0 / 3.0) - (1.0 - a)) / a.sqrt()
}

/// Directions drawn by `sample_emitter` from a scene lit by a map alone
/// fall into bins of (cos θ, φ) as ∫ environment_pdf dω over each bin
/// says (Mitsuba's and pbrt's chi-square test of a sampler against its
/// pdf); each sample's pdf and radiance are the functions' at its
/// direction.
#[test]
fn samples_follow_the_pdf() {
    let (_dir, scene) = sun_scene((24, 13), (5, 4), 11, 60.0);
    let kernel = Kernel::new(&scene);
    let (nz, nphi) = (12usize, 24usize);
    let bin = |d: Vec3| {
        let z = ((d.y as f64 + 1.0) / 2.0 * nz as f64) as usize;
        let phi = (d.z as f64).atan2(d.x as f64).rem_euclid(2.0 * PI);
        z.min(nz - 1) * nphi + ((phi / (2.0 * PI) * nphi as f64) as usize).min(nphi - 1)
    };
    let mut rng = Rng(5);
    let samples = 400_000;
    let mut counts = vec![0.0; nz * nphi];
    // A sample's pdf is read from the cell it was drawn in, the
    // function's from the cell its direction falls in: they may differ
    // within rounding of a cell's edge.
    let mut other_cell = 0;
    for _ in 0..samples {
        let u = Vec2::new(unit_f32(&mut rng), unit_f32(&mut rng));
        let s = kernel.sample_emitter(Vec3::ZERO, Vec3::Y, unit_f32(&mut rng), u);
        assert!(s.wi.length() > 0.99 && !s.delta && s.distance == f32::MAX);
        counts[bin(s.wi)] += 1.0;
        if s.wi.y > 0.0 {
            let pdf = kernel.environment_pdf(s.wi);
            if (s.pdf - pdf).abs() > 1e-3 * pdf {
                other_cell += 1;
            }
            let l = kernel.environment_radiance(s.wi);
            assert!((s.radiance - l).abs().max_element() <= 1e-3 * l.max_element());
        } else {
            assert_eq!(s.pdf, 0.0, "below the horizon");
        }
    }
    assert!(other_cell < samples / 1000, "{other_cell} pdfs differ");
    // Expected counts: the pdf integrated over each bin (16 × 16 points).
    let sub = 16;
    let mut statistic = 0.0;
    let mut dof = 0.0;
    let (mut pooled_count, mut pooled_expected) = (0.0, 0.0);
    for z_bin in 0..nz {
        for phi_bin in 0..nphi {
            let mut integral = 0.0;
            for a in 0..sub {
                let z = -1.0 + 2.0 * (z_bin as f64 + (a as f64 + 0.5) / sub as f64) / nz as f64;
                let r = (1.0 - z * z).sqrt();
                for b in 0..sub {
                    let phi =
                        2.0 * PI * (phi_bin as f64 + (b as f64 + 0.5) / sub as f64) / nphi as f64;
                    let d = DVec3::new(r * phi.cos(), z, r * phi.sin());
                    integral += kernel.environment_pdf(d.as_vec3()) as f64;
                }
            }
            let expected = integral * 4.0 * PI / (nz * nphi * sub * sub) as f64 * samples as f64;
            let count = counts[z_bin * nphi + phi_bin];
            if expected < 5.0 {
                pooled_count += count;
                pooled_expected += expected;
            } else {
                statistic += (count - expected) * (count - expected) / expected;
                dof += 1.0;
            }
        }
    }
    if pooled_expected > 0.0 {
        statistic += (pooled_count - pooled_expected).powi(2) / pooled_expected;
        dof += 1.0;
    }
    let z = chi_square_z(statistic, dof - 1.0);
    assert!(z < 4.0, "chi-square {statistic} over {dof} bins: z = {z}");
}

/// A constant environment: its colour × strength from every direction,
/// the uniform sphere's pdf, and samples spread evenly.
#[test]
fn the_constant_environment_is_the_same_everywhere() {
    let mut scene = floor();
    scene
        .set_environment(Some(&color_spec([0.5, 1.0, 2.0], 3.0)))
        .unwrap();
    let kernel = Kernel::new(&scene);
    let mut rng = Rng(9);
    let inv_4pi = (0.25 / PI) as f32;
    let mut moments = DVec3::ZERO;
    let mut squares = DVec3::ZERO;
    let n = 100_000;
    for _ in 0..n {
        let d = Vec3::from(unit_vector(&mut rng));
        assert_eq!(kernel.environment_radiance(d), Vec3::new(1.5, 3.0, 6.0));
        assert_eq!(kernel.environment_pdf(d), inv_4pi);
        let u = Vec2::new(unit_f32(&mut rng), unit_f32(&mut rng));
        let s = kernel.sample_emitter(Vec3::ZERO, d, unit_f32(&mut rng), u);
        assert_eq!(s.radiance, Vec3::new(1.5, 3.0, 6.0));
        assert_eq!(s.pdf, if s.wi.dot(d) > 0.0 { inv_4pi } else { 0.0 });
        moments += s.wi.as_dvec3();
        squares += s.wi.as_dvec3() * s.wi.as_dvec3();
    }
    let (mean, square) = (moments / n as f64, squares / n as f64);
    assert!(mean.abs().max_element() < 0.01, "{mean}");
    assert!(
        (square - DVec3::splat(1.0 / 3.0)).abs().max_element() < 0.01,
        "{square}"
    );
}

/// Without an environment: no radiance, no pdf.
#[test]
fn no_environment_gives_nothing() {
    let scene = floor();
    let kernel = Kernel::new(&scene);
    assert_eq!(kernel.environment_radiance(Vec3::Y), Vec3::ZERO);
    assert_eq!(kernel.environment_pdf(Vec3::Y), 0.0);
    assert!(scene.ignored_by_direct().is_none());
}

/// What `[environment]` says, and what it may not.
#[test]
fn the_environment_table() {
    let dir = tempfile::tempdir().unwrap();
    let sky = dir.path().join("sky.exr");
    write_exr(&sky, 4, 2, &[[1.0; 3]; 8]);
    let text = |table: &str| {
        format!(
            "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\nvfov = 40\nwidth = 8\nheight = 8\n\n[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\n\n{table}"
        )
    };
    let scene_with = |table: &str| Scene::from_toml(&text(table), &dir.path().join("scene.toml"));
    let scene = scene_with("[environment]\nimage = \"sky.exr\"\nstrength = 2\nrotation_deg = 30\n")
        .unwrap();
    let environment = scene.environment().unwrap();
    assert_eq!(environment.file(), Some(sky.as_path()));
    assert_eq!(
        environment.map.as_ref().unwrap().pixels[0],
        [2.0, 2.0, 2.0, 0.0]
    );
    assert!(scene.inputs().contains(&sky));
    let warning = scene.ignored_by_direct().unwrap();
    assert!(
        warning.contains("sky.exr") && warning.contains("direct integrator ignores"),
        "{warning}"
    );
    // `lambert info` says what the path integrator will see.
    let path = dir.path().join("lit.toml");
    std::fs::write(&path, text("[environment]\nimage = \"sky.exr\"\n")).unwrap();
    let info = common::lambert(&["info", path.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&info.stdout);
    assert!(
        stdout.contains("sky.exr (4 × 2 texels), strength 1, turned 0° about +Y")
            && stdout.contains("emitters (path integrator): 1 (0 emissive triangles)"),
        "{stdout}"
    );
    let scene = scene_with("[environment]\ncolor = [0.1, 0.2, 0.3]\n").unwrap();
    assert_eq!(scene.environment().unwrap().color, [0.1, 0.2, 0.3]);
    let error = |table: &str| scene_with(table).unwrap_err().to_string();
    for (table, expected) in [
        (
            "[environment]\ncolor = 1\nimage = \"sky.exr\"\n",
            "gives both color and image",
        ),
        (
            "[environment]\nstrength = 2\n",
            "needs color = [r, g, b] or image",
        ),
        (
            "[environment]\ncolor = 1\nstrength = -1\n",
            "environment.strength = -1 must be finite and non-negative",
        ),
        ("[environment]\ncolor = [1, -1, 0]\n", "environment.color"),
        ("[environment]\ncolour = 1\n", "unknown field `colour`"),
        ("[environment]\nimage = \"missing.hdr\"\n", "missing.hdr"),
    ] {
        let message = error(table);
        assert!(message.contains(expected), "{table}: {message}");
    }
}

/// A map that is missing, not an image, cut short, not finite or over the
/// cap: an error that names the file.
#[test]
fn bad_maps_are_refused_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let load = |name: &str| {
        let path = dir.path().join(name);
        let mut scene = floor();
        let error = scene
            .set_environment(Some(&map_spec(&path, 1.0, 0.0)))
            .unwrap_err();
        let message = error.to_string();
        assert!(message.contains(&path.display().to_string()), "{message}");
        message
    };
    assert!(load("missing.exr").contains("No such file"));
    std::fs::write(dir.path().join("text.exr"), "not an image").unwrap();
    assert!(load("text.exr").contains("not a Radiance HDR (.hdr) or OpenEXR (.exr) image"));
    let cut = dir.path().join("cut.exr");
    write_exr(&cut, 64, 32, &vec![[1.0; 3]; 64 * 32]);
    let bytes = std::fs::read(&cut).unwrap();
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    assert!(load("cut.exr").contains("not a readable OpenEXR image"));
    let cut = dir.path().join("cut.hdr");
    write_hdr(&cut, 64, 32, &vec![[1.0; 3]; 64 * 32]);
    let bytes = std::fs::read(&cut).unwrap();
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    assert!(load("cut.hdr").contains("not a readable Radiance HDR image"));
    write_exr(
        &dir.path().join("nan.exr"),
        2,
        2,
        &[[1.0; 3], [1.0, f32::NAN, 0.0], [1.0; 3], [1.0; 3]],
    );
    assert!(load("nan.exr").contains("pixel (1, 0) is [1.0, NaN, 0.0]"));
    // A small file that claims a huge map is refused before its pixels
    // are allocated.
    let header = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 16384 +X 16384\n\x02\x02\x40\x00";
    std::fs::write(dir.path().join("claims.hdr"), header).unwrap();
    assert!(load("claims.hdr").contains("its header claims 16384 × 16384 pixels"));
    // A sparse file one byte over the cap takes no room on disk.
    let big = std::fs::File::create(dir.path().join("big.hdr")).unwrap();
    big.set_len(MAX_ENVIRONMENT_BYTES + 1).unwrap();
    assert!(load("big.hdr").contains("more than the 1 GiB that lambert reads of one file"));
}

/// `--environment` lights a model file alone: a colour, or a map read from
/// where the command runs; the direct integrator renders it as before and
/// warns that it ignores it.
#[test]
fn the_environment_option() {
    let dir = tempfile::tempdir().unwrap();
    let sky = dir.path().join("sky.hdr");
    write_hdr(&sky, 4, 2, &[[1.0; 3]; 8]);
    let model = dir.path().join("triangle.obj");
    std::fs::write(&model, "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let plain = dir.path().join("plain.pfm");
    let lit = dir.path().join("lit.pfm");
    let args = |out: &Path| {
        vec![
            "render".to_string(),
            model.display().to_string(),
            "-o".into(),
            out.display().to_string(),
            "--device".into(),
            "cpu".into(),
            "--width".into(),
            "32".into(),
            "--height".into(),
            "24".into(),
        ]
    };
    let run = |extra: &[&str], out: &Path| {
        let mut all = args(out);
        all.extend(extra.iter().map(|s| s.to_string()));
        let all: Vec<&str> = all.iter().map(String::as_str).collect();
        common::lambert(&all)
    };
    assert!(run(&[], &plain).status.success());
    let output = run(
        &[
            "--environment",
            sky.to_str().unwrap(),
            "--environment-strength",
            "2",
        ],
        &lit,
    );
    assert!(output.status.success(), "{}", common::stderr(&output));
    let stderr = common::stderr(&output);
    assert!(
        stderr.contains("sky.hdr") && stderr.contains("direct integrator ignores it"),
        "{stderr}"
    );
    assert_eq!(std::fs::read(&plain).unwrap(), std::fs::read(&lit).unwrap());
    // The map may not be the output.
    let output = run(&["--environment", sky.to_str().unwrap()], &sky);
    assert!(!output.status.success());
    let output = run(&["--environment", "1,2,-3"], &lit);
    assert!(
        common::stderr(&output)
            .contains("--environment = [1.0, 2.0, -3.0] must be finite and non-negative"),
        "{}",
        common::stderr(&output)
    );
    // Two numbers are no colour: a file of that name, not found.
    let output = run(&["--environment", "0.5,1"], &lit);
    assert!(
        common::stderr(&output).contains("0.5,1: No such file"),
        "{}",
        common::stderr(&output)
    );
    let output = run(
        &["--environment", "0.2", "--environment-rotation", "inf"],
        &lit,
    );
    assert!(common::stderr(&output).contains("--environment-rotation = inf must be finite"));
}

/// A part's settings hash covers the environment: parts rendered under
/// different skies do not merge.
#[test]
fn the_parts_hash_covers_the_environment() {
    let hash = |scene: &Scene| lambert::parts::settings_hash(scene, scene.view(), "cpu");
    let mut scene = floor();
    let bare = hash(&scene);
    scene
        .set_environment(Some(&color_spec([1.0; 3], 1.0)))
        .unwrap();
    let one = hash(&scene);
    scene
        .set_environment(Some(&color_spec([1.0; 3], 2.0)))
        .unwrap();
    let two = hash(&scene);
    assert!(bare != one && one != two && bare != two);
    scene.set_environment(None).unwrap();
    assert_eq!(hash(&scene), bare);
}
