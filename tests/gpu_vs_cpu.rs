//! GPU (lavapipe on CI) against the CPU reference on every bundled scene, with `lambert diff`'s tolerance.

mod common;

use common::*;
use lambert::diff::{Tolerance, compare};

fn check(name: &str) {
    let scene = load(name);
    let gpu = render_gpu(&scene);
    let cpu = render_cpu(&scene);
    let stats = compare(&gpu, &cpu, &Tolerance::default()).unwrap();
    println!("{name}: GPU vs CPU\n{stats}");
    assert!(
        stats.passed,
        "{name}: GPU and CPU differ beyond tolerance:\n{stats}"
    );
    // Not a free pass for mismatched hits: they are bounded explicitly.
    assert!(
        stats.prim_mismatches as f64 <= 1e-3 * stats.pixels as f64,
        "{name}: {} pixels hit different primitives",
        stats.prim_mismatches
    );
    // Something was actually drawn: the scene's geometry is on screen.
    let hits = cpu
        .prims
        .iter()
        .filter(|&&p| p != lambert::layout::NO_HIT)
        .count();
    assert!(hits > 0, "{name}: no camera ray hit anything");
}

#[test]
fn triangle_head_on() {
    check("triangle_head_on");
}

#[test]
fn triangle_oblique() {
    check("triangle_oblique");
}

#[test]
fn triangle_back_facing() {
    check("triangle_back");
}

#[test]
fn edge_cases() {
    check("edge_cases");
}

#[test]
fn spheres() {
    check("spheres");
}

#[test]
fn cornell_room() {
    check("cornell");
}

#[test]
fn closed_mesh_with_shadows() {
    check("bunny");
}

#[test]
fn mesh_of_11k_triangles() {
    let scene = load("dragon");
    assert!(scene.triangles().len() >= 10_000);
    check("dragon");
}

#[test]
fn cpu_reference_agrees_with_f64_oracle() {
    for name in ["cornell", "spheres", "edge_cases", "triangle_oblique"] {
        let scene = load(name);
        let (cpu, oracle) = (render_cpu(&scene), render_oracle(&scene));
        let stats = compare(&cpu, &oracle, &Tolerance::default()).unwrap();
        println!("{name}: CPU f32 vs f64 oracle\n{stats}");
        assert!(
            stats.passed,
            "{name}: f32 and f64 differ beyond tolerance:\n{stats}"
        );
    }
}

#[test]
fn edge_case_scene_behaves() {
    let scene = load("edge_cases");
    let (w, h) = (scene.view().camera.width, scene.view().camera.height);
    for r in [render_gpu(&scene), render_cpu(&scene)] {
        // The triangle whose plane holds the eye (mesh 1, primitive 4) is
        // never hit: its rays start in its plane or run parallel to it.
        assert!(!r.prims.contains(&4), "the in-plane triangle was hit");
        // Rays along the shared edges and through the shared vertex hit the
        // fan (primitives 0–3) rather than slipping through.
        for (x, y) in [
            (w / 2, h / 2),
            (w / 2, h / 2 - 3),
            (w / 2 + 3, h / 2),
            (w / 2, h / 2 + 3),
        ] {
            let prim = r.prims[(y * w + x) as usize];
            assert!(prim < 4, "pixel ({x}, {y}) on a shared edge hit {prim}");
        }
        // No NaN anywhere.
        assert!(r.image.rgb.iter().flatten().all(|v| v.is_finite()));
    }
}

/// The scene's words, larger than one storage binding, are split over
/// two bindings: a binding limit made just over half their size puts the
/// BVH (after the triangles and their normals) in the high binding on the
/// bunny and the dragon, and the images stay the same.
#[test]
fn scenes_split_across_bindings_render_the_same() {
    for name in ["bunny", "dragon"] {
        let scene = load(name);
        let mut gpu = open_gpu();
        let words = (scene.triangles().len() + scene.normals().len()) * 48
            + scene.bvh().nodes.len() * 80
            + scene.bvh().blocks.len() * 160;
        // Just over half of them (and the small arrays after the BVH: the
        // materials, lights, textures), rounded to 256 bytes.
        gpu.limits.max_storage_buffer_binding_size = (words as u64 / 2 + 4096).div_ceil(256) * 256;
        // Storage buffers, which split (lavapipe's default, textures, do not):
        // the image must equal the default's, bit for bit.
        let mut renderer = lambert::gpu::GpuRenderer::with_bvh_storage(
            gpu,
            &scene,
            lambert::gpu::BvhStorage::Buffers,
        )
        .expect("split upload");
        // The BVH follows the triangles (the bunny's normals too, as many
        // bytes as its triangles), so it lies in the high binding.
        for array in ["BVH nodes", "BVH leaf blocks"] {
            assert!(
                renderer.split_arrays.contains(&array),
                "{name}: {array} not in the high binding: {:?}",
                renderer.split_arrays
            );
        }
        let split = renderer
            .render(scene.view(), &lambert::progress::Progress::hidden())
            .unwrap()
            .0;
        let stats = lambert::diff::compare(
            &split,
            &render_gpu(&scene),
            &lambert::diff::Tolerance::default(),
        )
        .unwrap();
        assert_eq!(
            stats.max_abs, 0.0,
            "{name}: splitting changed the image\n{stats}"
        );
        assert_eq!(stats.prim_mismatches, 0);
    }
}

/// An adapter with WebGPU's default 8 storage buffers a stage (too few
/// for the wavefronts' passes, enough for the megakernel's) renders in the
/// megakernel, direct and path-traced, and gives the image the wavefront
/// gives where it fits: the same bits.
#[test]
fn an_adapter_with_webgpus_default_bindings_renders_in_the_megakernel() {
    use lambert::gpu::GpuRenderer;
    use lambert::scene::{Integrator, Scene};
    let small = |scene: Scene, integrator| {
        let mut settings = scene.default_settings();
        settings.integrator = integrator;
        (settings.view.camera.width, settings.view.camera.height) = (96, 72);
        settings.view.spp = 2;
        scene.with_settings(&settings)
    };
    // The wavefront is the default for shadowed direct lighting and for a
    // textured path-traced scene.
    let textured = Scene::load(&asset("scenes/meshes/textured.glb")).expect("bundled model");
    for (name, scene) in [
        (
            "cornell, direct",
            small(load("cornell"), Integrator::Direct),
        ),
        ("textured.glb, path", small(textured, Integrator::Path)),
    ] {
        let mut gpu = open_gpu();
        gpu.limits.max_storage_buffers_per_shader_stage = 8;
        let mut few = GpuRenderer::new(gpu, &scene).expect("8 storage buffers");
        let mut wide = GpuRenderer::new(open_gpu(), &scene).unwrap();
        assert!(!few.is_wavefront(), "{name}: the wavefront chosen with 8");
        assert!(
            wide.is_wavefront(),
            "{name}: the wavefront not chosen where it fits"
        );
        let image = |r: &mut GpuRenderer| {
            r.render(scene.view(), &lambert::progress::Progress::hidden())
                .unwrap()
                .0
        };
        let (a, b) = (image(&mut few), image(&mut wide));
        assert_eq!(a.image.rgb, b.image.rgb, "{name}");
        assert_eq!(a.prims, b.prims, "{name}");
    }
}

/// The wavefront render (shadow rays traced apart from the camera rays; the default at any spp where
/// shadows are traced) and the megakernel give the same image, bit for bit (colour, variance and
/// primitive): at 1 and 3 spp on five scenes, at 40 spp (more than a
/// dispatch takes on llvmpipe: the sums carried between dispatches), and
/// with 40 lights (a camera ray's shadow rays queued together, their terms
/// added in light order), which also agree with the CPU path.
#[test]
fn the_wavefront_renders_as_the_megakernel_does() {
    for name in ["cornell", "spheres", "bunny", "dragon", "edge_cases"] {
        let mut scene = load(name);
        for spp in [1, 3] {
            scene.view_mut().spp = spp;
            wavefront_as_megakernel(&scene, &format!("{name} at {spp} spp"));
        }
    }
    for name in ["spheres", "edge_cases"] {
        let mut scene = load(name);
        scene.view_mut().spp = 40;
        wavefront_as_megakernel(&scene, &format!("{name} at 40 spp"));
    }
    let mut many = ring_of_lights();
    for spp in [1, 4] {
        many.view_mut().spp = spp;
        let wavefront = wavefront_as_megakernel(&many, &format!("40 lights at {spp} spp"));
        let stats = compare(&wavefront, &render_cpu(&many), &Tolerance::default()).unwrap();
        assert!(stats.passed, "40 lights at {spp} spp: GPU vs CPU\n{stats}");
    }
}

/// 40 point lights in a ring above a ball that shades a larger one below:
/// a camera ray's shadow rays queued together, their terms added in light
/// order.
fn ring_of_lights() -> lambert::Scene {
    let lights: String = (0..40)
        .map(|i| {
            let a = i as f64 * std::f64::consts::TAU / 40.0;
            let (x, z) = (0.8 * a.cos(), 0.8 * a.sin());
            format!("[[point_light]]\nposition = [{x}, 3.0, {z}]\nintensity = [0.5, 0.5, 0.5]\n")
        })
        .collect();
    scene(&format!(
        "[camera]\neye = [0.0, 2.5, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 40.0\nwidth = 48\nheight = 40\n\
         [[sphere]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n\
         [[sphere]]\ncenter = [0.0, 1.6, 0.0]\nradius = 0.3\n{lights}"
    ))
}

/// Adaptive sampling's later passes, a list of pixels rendered again with
/// another seed, go through the wavefront too: the same bits as the
/// megakernel's `render_pixel_list`, at 1, 3 and 40 samples (more than a
/// dispatch takes on llvmpipe), on scattered and repeated pixels, with one
/// light and with 40; and within tolerance of the CPU path.
#[test]
fn pixel_lists_render_in_the_wavefront_as_the_megakernel_does() {
    use lambert::gpu::{GpuRenderer, ShadowDispatch};
    let many = ring_of_lights();
    for (name, scene) in [
        ("bunny", load("bunny")),
        ("spheres", load("spheres")),
        ("40 lights", many),
    ] {
        let (w, h) = (scene.view().camera.width, scene.view().camera.height);
        // Every 7th pixel, then some twice, out of order.
        let mut pixels: Vec<[u32; 2]> = (0..w * h).step_by(7).map(|i| [i % w, i / w]).collect();
        pixels.extend([[w / 2, h / 2], [0, 0], [w / 2, h / 2], [w - 1, h - 1]]);
        let mut renderer = GpuRenderer::new(open_gpu(), &scene).expect("scene uploads");
        for spp in [1, 3, 40] {
            let view = lambert::camera::View {
                spp,
                seed: 0x5eed + spp,
                ..scene.view().clone()
            };
            renderer.shadow_dispatch = ShadowDispatch::Wavefront;
            let wavefront = renderer.render_pixel_list(&view, &pixels).unwrap();
            renderer.shadow_dispatch = ShadowDispatch::Megakernel;
            let mega = renderer.render_pixel_list(&view, &pixels).unwrap();
            let bits =
                |r: &[[f32; 4]]| -> Vec<u32> { r.iter().flatten().map(|c| c.to_bits()).collect() };
            assert!(
                bits(&wavefront) == bits(&mega),
                "{name} at {spp} spp: the pixel list in the wavefront differs from the megakernel's"
            );
            let cpu = lambert::cpu::render_pixel_list(&scene, &view, &pixels);
            for (i, (g, c)) in wavefront.iter().zip(&cpu).enumerate() {
                for k in 0..3 {
                    assert!(
                        (g[k] - c[k]).abs() <= 1e-3 * c[k].abs().max(1.0),
                        "{name} at {spp} spp, pixel {:?}: GPU {g:?}, CPU {c:?}",
                        pixels[i]
                    );
                }
            }
        }
    }
}

/// Renders `scene` in the wavefront (its default) and in the megakernel;
/// fails unless they are the same bits. Returns the image.
fn wavefront_as_megakernel(scene: &lambert::Scene, label: &str) -> lambert::output::Rendered {
    use lambert::gpu::{GpuRenderer, ShadowDispatch};
    let hidden = lambert::progress::Progress::hidden();
    let mut renderer = GpuRenderer::new(open_gpu(), scene).expect("scene uploads");
    assert_eq!(
        renderer.shadow_dispatch,
        ShadowDispatch::Wavefront,
        "{label}: the wavefront by default, at any spp"
    );
    assert!(renderer.is_wavefront(), "{label}");
    let wavefront = renderer.render(scene.view(), &hidden).unwrap().0;
    renderer.shadow_dispatch = ShadowDispatch::Megakernel;
    let mega = renderer.render(scene.view(), &hidden).unwrap().0;
    let bits = |r: &lambert::output::Rendered| {
        let rgb: Vec<u32> = r.image.rgb.iter().flatten().map(|c| c.to_bits()).collect();
        let var: Vec<u32> = r.variance.iter().map(|v| v.to_bits()).collect();
        (rgb, var, r.prims.clone())
    };
    assert!(
        bits(&wavefront) == bits(&mega),
        "{label}: the wavefront differs"
    );
    println!("{label}: wavefront = megakernel, bit for bit");
    wavefront
}

/// The workgroups dealt to llvmpipe's threads in turn (the shader's
/// `spread_workgroup` for lists of rays, a render tile's rows in layers
/// for `tile_pixel`, both sized by `Gpu::cpu_threads`) cover the
/// dispatch's work once, whatever the number of threads assumed: renders
/// in both paths and ray queries come out the same bits for 1 to 7 of
/// them, remainders included (a wrong deal drops or repeats pixels).
#[test]
fn workgroups_spread_over_any_thread_count_change_no_pixel_or_hit() {
    use lambert::gpu::{AdapterRequest, Gpu, GpuOptions, GpuRenderer, ShadowDispatch};
    let hidden = lambert::progress::Progress::hidden();
    let mut scene = load("bunny");
    scene.view_mut().camera.width = 72;
    scene.view_mut().camera.height = 40;
    scene.view_mut().spp = 3;
    let rays = lambert::rays::camera_rays(&scene);
    let outputs = |threads: &str| {
        let request = AdapterRequest {
            options: GpuOptions {
                llvmpipe_threads: Some(threads.to_string()),
                ..GpuOptions::default()
            },
            ..AdapterRequest::default()
        };
        let gpu = Gpu::open(&request, false).expect("an adapter (lavapipe on CI)");
        if gpu.is_llvmpipe() {
            assert_eq!(
                gpu.cpu_threads().to_string(),
                threads,
                "LP_NUM_THREADS is followed"
            );
        }
        let mut renderer = GpuRenderer::new(gpu, &scene).expect("scene uploads");
        let mut images = Vec::new();
        for dispatch in [ShadowDispatch::Wavefront, ShadowDispatch::Megakernel] {
            renderer.shadow_dispatch = dispatch;
            let r = renderer.render(scene.view(), &hidden).unwrap().0;
            images.push((bits(&r), r.prims.clone()));
        }
        let hits = renderer
            .trace_rays(&rays, false, scene.default_settings().intersect)
            .unwrap();
        let hits: Vec<[u32; 4]> = hits
            .iter()
            .map(|h| [h.t.to_bits(), h.prim, h.u.to_bits(), h.v.to_bits()])
            .collect();
        (images, hits)
    };
    let one = outputs("1");
    assert!(
        one.1.iter().any(|h| h[1] != lambert::layout::NO_HIT),
        "the rays hit the bunny"
    );
    for threads in ["2", "3", "5", "7"] {
        assert!(
            outputs(threads) == one,
            "{threads} threads assumed: the output differs"
        );
    }
}
