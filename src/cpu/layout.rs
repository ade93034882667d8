//! Data layout, the twin of shaders/layout.wgsl: the kernel's imports (for
//! every stage), its constants, rays, hits and the per-ray
//! shear, and `Kernel`, what the shader's bindings hold. Written once for
//! both precisions: `kernel!` (kernel.rs) expands it into `cpu::f32` and
//! `cpu::f64`, whose `Real`, `Vec3` and `Vec4` it takes.

/// The stage's items, expanded into the module that invokes it (`kernel!`).
macro_rules! layout {
    () => {
        use crate::bvh::{MAX_DEPTH, STACK_SIZE};
        use crate::camera::View;
        use crate::layout::{
            BVH_WIDTH, BvhNode, CompressedNode, FLAG_ATTRIBUTES, FLAG_MASKED, FLAG_SMOOTH,
            LEAF_BIT, LIGHT_DIRECTIONAL, LIGHT_SPOT, META_LEAF, NO_HIT, NO_TEXTURE, PrimBlock,
            leaf_range,
        };
        use crate::scene::{Intersect, Scene};

        /// Widens a box's exit distance so that rounding cannot cull a box the ray
        /// grazes, as in the shader.
        pub(crate) const BOX_SLACK: Real = 1.000001;

        /// Unit roundoff (pbrt's MachineEpsilon), for error bounds.
        pub(crate) const MACHINE_EPSILON: Real = Real::EPSILON * 0.5;

        /// "No hit yet" distance, as in the shader.
        pub const FAR: Real = Real::MAX;

        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct Ray {
            pub origin: Vec3,
            pub tmin: Real,
            pub dir: Vec3,
            pub tmax: Real,
        }

        impl Ray {
            /// A ray of a ray query, in this precision.
            pub fn from_query(ray: &crate::layout::Ray) -> Ray {
                Ray {
                    origin: vec3(ray.origin),
                    tmin: ray.tmin as Real,
                    dir: vec3(ray.dir),
                    tmax: ray.tmax as Real,
                }
            }
        }

        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct Hit {
            pub t: Real,
            pub prim: u32,
            pub u: Real,
            pub v: Real,
        }

        impl Hit {
            /// A ray query's answer, in this precision.
            pub fn from_query(hit: &crate::layout::Hit) -> Hit {
                Hit {
                    t: hit.t as Real,
                    prim: hit.prim,
                    u: hit.u as Real,
                    v: hit.v as Real,
                }
            }
        }

        /// Precomputed per ray for the watertight test: axes permuted so that the
        /// direction's largest component is z, and the shear onto +z.
        #[derive(Clone, Copy, Debug)]
        pub struct Shear {
            pub axes: [usize; 3],
            pub s: Vec3,
            /// The power of two `prepare_ray` scaled the direction by: a hit's
            /// distance along the scaled ray times this is its distance along the
            /// ray as given.
            pub t_scale: Real,
        }

        pub struct Surface {
            pub position: Vec3,
            /// How far `position` may be off the surface, per axis (self_hit_bound).
            pub error: Vec3,
            pub geometric_normal: Vec3,
            pub shading_normal: Vec3,
            pub albedo: Vec3,
            pub emission: Vec3,
        }

        fn vec3(v: [f32; 3]) -> Vec3 {
            Vec3::new(v[0] as Real, v[1] as Real, v[2] as Real)
        }

        #[inline(always)]
        fn vec4(v: [f32; 4]) -> Vec4 {
            Vec4::new(v[0] as Real, v[1] as Real, v[2] as Real, v[3] as Real)
        }

        /// A scene seen from one view: what the shader's bindings hold.
        pub struct Kernel<'a> {
            pub camera: CameraBasis,
            pub scene: &'a Scene,
            /// The view's samples per pixel and jitter seed.
            spp: u32,
            seed: u32,
            background: Vec3,
            ambient: Vec3,
            strata_x: u32,
            /// The ray/triangle test: the scene's, unless a query asks for another.
            pub intersect: Intersect,
            /// Whether node visits take `Scalar::intersect_boxes_ymm` (the CPU has 8-lane
            /// vector registers and fused multiply-adds).
            ymm_boxes: bool,
            /// The GPU's compressed nodes of the scene's BVH: with them, `trace`
            /// traverses as the shader does (`trace_compressed`), the twin that
            /// GPU results are compared with.
            pub compressed: Option<&'a [CompressedNode]>,
            /// Whether some triangle is alpha-masked (the shader's HAS_ALPHA_MASK).
            alpha_mask: bool,
            /// The scene's texture store (the shader's `textures`).
            textures: Textures<'a>,
            /// The camera rays' cone spread (the shader's `params.cone_spread`).
            cone_spread: f32,
            /// The GPU's short stack: entries `trace_compressed` keeps before the
            /// oldest spill (`cwbvh::short_stack`; `MAX_DEPTH`, none spill).
            pub stack_entries: usize,
            /// Whether samples are path traced (`Integrator::Path`; the
            /// shader's PATH_TRACE), and the most surfaces a path hits.
            path: bool,
            max_depth: u32,
        }

        impl<'a> Kernel<'a> {
            /// `scene` seen from its default view (ray queries use no camera).
            pub fn new(scene: &'a Scene) -> Kernel<'a> {
                Kernel::new_for(scene, <Real as Scalar>::has_ymm_boxes())
            }

            /// `new`, with node visits through `Scalar::intersect_boxes_ymm` or not: the
            /// SIMD kernels' tests compare each against the portable one.
            pub fn new_for(scene: &'a Scene, ymm_boxes: bool) -> Kernel<'a> {
                Kernel::with_view(scene, &scene.view, ymm_boxes)
            }

            /// `scene` seen from `view` rather than its default (`Scene::view`).
            pub fn with_view(scene: &'a Scene, view: &View, ymm_boxes: bool) -> Kernel<'a> {
                let camera = scene.local_camera(&view.camera);
                // From the f32 basis in both precisions, as the GPU's is.
                let basis = crate::camera::f32::CameraBasis::new(&camera);
                Kernel {
                    camera: CameraBasis::new(&camera),
                    scene,
                    spp: view.spp,
                    seed: view.seed,
                    background: vec3(scene.background),
                    ambient: vec3(scene.ambient),
                    strata_x: crate::camera::strata_columns(view.spp),
                    intersect: scene.intersect,
                    ymm_boxes,
                    alpha_mask: scene.has_alpha_mask(),
                    textures: Textures {
                        words: scene.textures.words(),
                    },
                    cone_spread: crate::texture::cone_spread(
                        basis.tan_half_y,
                        basis.height,
                        view.spp,
                    ),
                    compressed: None,
                    stack_entries: MAX_DEPTH,
                    path: scene.integrator == crate::scene::Integrator::Path,
                    max_depth: scene.max_depth,
                }
            }
        }
    };
}
pub(crate) use layout;
