//! The BSDF, the twin of shaders/bsdf.wgsl, function by function with the
//! same names: Lambert and glTF 2.0's metallic-roughness BRDF (appendix B:
//! GGX D with α = roughness², the height-correlated Smith visibility,
//! Schlick's Fresnel with F0 = 0.04 or the base colour, mixed by
//! metallic), the specular lobe sampled by visible normals (Heitz 2018),
//! and the shading frame (Duff et al. 2017), in the local frame (z the
//! shading normal, wo towards the viewer, wi towards the light). Each
//! operation rounds on its own in the shader's order (Rust neither fuses
//! nor reassociates; the shader's `rounded` stops its compiler doing so),
//! so the f32 twin computes the GPU's bits. Formulas, references and
//! measurements in docs/rendering.md ("The BSDF"); tests in tests/bsdf.rs.
//!
//! Written once for both precisions: `kernel!` (kernel.rs) expands it into
//! `cpu::f32` and `cpu::f64`, whose `Real`, `Vec2` and `Vec3` it takes.

/// The stage's items, expanded into the module that invokes it (`kernel!`).
macro_rules! bsdf {
    () => {
        /// A floor on GGX's α: a smooth surface (roughness 0) is a lobe about
        /// a milliradian wide, not a delta the integrator would need a case
        /// for; D peaks at 1/(π α²) = 3.2e5, well within f32.
        pub const ALPHA_MIN: Real = 0.001;
        /// The dielectric's reflectance at normal incidence (glTF: IOR 1.5).
        pub const DIELECTRIC_F0: Real = 0.04;
        /// Where both lobes reflect, each is chosen at least this often,
        /// which bounds f·cos/pdf by 1/LOBE_PROBABILITY_MIN.
        pub const LOBE_PROBABILITY_MIN: Real = 0.1;

        /// A surface's BSDF: `kind` a `layout::MATERIAL_*`; metallic and
        /// the perceptual roughness in [0, 1] (unused by Lambert).
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct BsdfParams {
            pub base_color: Vec3,
            pub metallic: Real,
            pub roughness: Real,
            pub kind: u32,
        }

        /// A sampled direction: weight = f·|cos θi|/pdf; `ok` false where
        /// none was made (wo below the horizon, or a reflection below it).
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct BsdfSample {
            pub wi: Vec3,
            pub weight: Vec3,
            pub pdf: Real,
            pub ok: bool,
        }

        /// An orthonormal frame about a unit normal (the shader's mat3x3
        /// columns).
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct Frame {
            pub tangent: Vec3,
            pub bitangent: Vec3,
            pub normal: Vec3,
        }

        /// Duff et al., "Building an Orthonormal Basis, Revisited" (JCGT
        /// 2017).
        #[inline(always)]
        pub fn frame_from_normal(n: Vec3) -> Frame {
            let sign = if n.z < 0.0 { -1.0 } else { 1.0 };
            let a = -1.0 / (sign + n.z);
            let b = n.x * n.y * a;
            Frame {
                tangent: Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
                bitangent: Vec3::new(b, sign + n.y * n.y * a, -n.y),
                normal: n,
            }
        }

        #[inline(always)]
        pub fn to_local(frame: Frame, v: Vec3) -> Vec3 {
            Vec3::new(
                dot3(frame.tangent, v),
                dot3(frame.bitangent, v),
                dot3(frame.normal, v),
            )
        }

        #[inline(always)]
        pub fn to_world(frame: Frame, v: Vec3) -> Vec3 {
            frame.tangent * v.x + frame.bitangent * v.y + frame.normal * v.z
        }

        /// GGX's α for a perceptual roughness (glTF: α = roughness²),
        /// floored.
        #[inline(always)]
        pub fn ggx_alpha(roughness: Real) -> Real {
            (roughness * roughness).max(ALPHA_MIN)
        }

        #[inline(always)]
        pub fn ggx_alpha2(roughness: Real) -> Real {
            let alpha = ggx_alpha(roughness);
            alpha * alpha
        }

        /// Trowbridge-Reitz D(h) for unit h above the surface, its
        /// denominator sin²θ + α²cos²θ from h's components: (n·h)²(α² − 1)
        /// + 1 would cancel to nothing in f32 near a sharp lobe's peak.
        #[inline(always)]
        pub fn ggx_d(h: Vec3, alpha2: Real) -> Real {
            let t = h.x * h.x + h.y * h.y + alpha2 * (h.z * h.z);
            alpha2 / (PI * t * t)
        }

        /// √(cos²θ + α² sin²θ) of unit w: Smith's Λ(w) = (√(1 + α² tan²θ)
        /// − 1)/2 is this over cos θ, less one, halved.
        #[inline(always)]
        pub fn smith_root(w: Vec3, alpha2: Real) -> Real {
            let sin2 = w.x * w.x + w.y * w.y;
            safe_sqrt(w.z * w.z + alpha2 * sin2)
        }

        /// Schlick's (1 − cos)⁵.
        #[inline(always)]
        pub fn schlick_weight(cos_theta: Real) -> Real {
            approx_pow5(1.0 - cos_theta.max(0.0))
        }

        #[inline(always)]
        fn mean3(c: Vec3) -> Real {
            (c.x + c.y + c.z) / 3.0
        }

        /// The metallic-roughness BRDF f(wo, wi), both above the surface:
        /// glTF 2.0 appendix B's formulas in its order.
        #[inline(always)]
        pub fn metallic_roughness_f(p: BsdfParams, wo: Vec3, wi: Vec3) -> Vec3 {
            let alpha2 = ggx_alpha2(p.roughness);
            let h = normalize3(wo + wi);
            let w5 = schlick_weight(dot3(wo, h));
            // V·D, V the height-correlated Smith visibility G2/(4 cos θo
            // cos θi).
            let visibility = 0.5 / (wi.z * smith_root(wo, alpha2) + wo.z * smith_root(wi, alpha2));
            let specular = visibility * ggx_d(h, alpha2);
            let f_dielectric = DIELECTRIC_F0 + (1.0 - DIELECTRIC_F0) * w5;
            let f_metal = p.base_color + (1.0 - p.base_color) * w5;
            let dielectric = p.base_color * INV_PI * (1.0 - f_dielectric) + specular * f_dielectric;
            dielectric * (1.0 - p.metallic) + f_metal * specular * p.metallic
        }

        /// f(wo, wi)·cos θi in the local frame; 0 unless both are above the
        /// surface.
        #[inline(always)]
        pub fn bsdf_eval(p: BsdfParams, wo: Vec3, wi: Vec3) -> Vec3 {
            if wo.z <= 0.0 || wi.z <= 0.0 {
                return Vec3::ZERO;
            }
            if p.kind == crate::layout::MATERIAL_LAMBERT {
                return p.base_color * (INV_PI * wi.z);
            }
            metallic_roughness_f(p, wo, wi) * wi.z
        }

        /// The probability of sampling the specular lobe for wo: the lobes'
        /// reflectances estimated with cos θo for the half vector's cosine
        /// (colours by their mean), kept in [LOBE_PROBABILITY_MIN, 1 − that]
        /// where both reflect; 1 where the diffuse lobe is black.
        #[inline(always)]
        pub fn specular_probability(p: BsdfParams, cos_o: Real) -> Real {
            let w5 = schlick_weight(cos_o);
            let f0 = DIELECTRIC_F0 * (1.0 - p.metallic) + mean3(p.base_color) * p.metallic;
            let specular = f0 + (1.0 - f0) * w5;
            let f_dielectric = DIELECTRIC_F0 + (1.0 - DIELECTRIC_F0) * w5;
            let diffuse = (1.0 - p.metallic) * (1.0 - f_dielectric) * mean3(p.base_color);
            if diffuse <= 0.0 {
                return 1.0;
            }
            (specular / (specular + diffuse))
                .clamp(LOBE_PROBABILITY_MIN, 1.0 - LOBE_PROBABILITY_MIN)
        }

        /// The solid-angle pdf of `bsdf_sample` at wi; 0 unless both are
        /// above the surface. The specular lobe's: D(h)·G1(wo)/(4 cos θo)
        /// (Heitz 2018, eq. 17 with the reflection's Jacobian 1/(4 wo·h)),
        /// G1(wo) = 2 cos θo/(cos θo + smith_root(wo)).
        #[inline(always)]
        pub fn bsdf_pdf(p: BsdfParams, wo: Vec3, wi: Vec3) -> Real {
            if wo.z <= 0.0 || wi.z <= 0.0 {
                return 0.0;
            }
            let diffuse = wi.z * INV_PI;
            if p.kind == crate::layout::MATERIAL_LAMBERT {
                return diffuse;
            }
            let alpha2 = ggx_alpha2(p.roughness);
            let h = normalize3(wo + wi);
            let specular = ggx_d(h, alpha2) / (2.0 * (wo.z + smith_root(wo, alpha2)));
            let q = specular_probability(p, wo.z);
            q * specular + (1.0 - q) * diffuse
        }

        /// A cosine-distributed direction about z (pdf cos θ/π), by polar
        /// coordinates on the unit disc.
        #[inline(always)]
        pub fn sample_cosine(u: Vec2) -> Vec3 {
            let (sin, cos) = approx_sin_cos(TWO_PI * u.y);
            let r = u.x.sqrt();
            Vec3::new(r * cos, r * sin, safe_sqrt(1.0 - u.x))
        }

        /// A microfacet normal distributed as GGX's visible normals seen
        /// from wo: Heitz, "Sampling the GGX Distribution of Visible
        /// Normals" (JCGT 2018), listing 1, isotropic, with T2 = Vh × T1
        /// written out and the lift off the disc computed without
        /// cancellation.
        #[inline(always)]
        pub fn sample_ggx_visible_normal(wo: Vec3, alpha: Real, u: Vec2) -> Vec3 {
            // The view direction stretched to the hemisphere configuration.
            let vh = normalize3(Vec3::new(alpha * wo.x, alpha * wo.y, wo.z));
            let length2 = vh.x * vh.x + vh.y * vh.y;
            let length = safe_sqrt(length2);
            let t1 = if length2 > 0.0 {
                Vec3::new(-vh.y, vh.x, 0.0) * (1.0 / length)
            } else {
                Vec3::new(1.0, 0.0, 0.0)
            };
            let t2 = Vec3::new(-vh.z * t1.y, vh.z * t1.x, length);
            // A point on the disc, warped to the visible half of the
            // hemisphere's projection, then lifted onto the hemisphere.
            let (sin, cos) = approx_sin_cos(TWO_PI * u.y);
            let r = u.x.sqrt();
            let d1 = r * cos;
            let t2_disc = r * sin;
            let s = 0.5 * (1.0 + vh.z);
            let q = safe_sqrt(1.0 - d1 * d1);
            let d2 = (1.0 - s) * q + s * t2_disc;
            // √(1 − d1² − d2²) cancels to noise at the disc's rim in f32.
            // It is (q − d2)(q + d2) = s a · (2(1 − s) q + s b), a = q −
            // t2_disc, b = q + t2_disc, a b = 1 − r² = 1 − u.x: the one of a
            // and b that does not cancel directly, the other as 1 − u.x over
            // it.
            let (a, b) = if t2_disc < 0.0 {
                let a = q - t2_disc;
                (a, (1.0 - u.x) / a)
            } else {
                let b = q + t2_disc;
                ((1.0 - u.x) / b, b)
            };
            let lift = safe_sqrt(s * a * (2.0 * (1.0 - s) * q + s * b));
            let nh = t1 * d1 + t2 * d2 + vh * lift;
            // Back to the ellipsoid configuration.
            let z = if nh.z < 0.0 { 0.0 } else { nh.z };
            normalize3(Vec3::new(alpha * nh.x, alpha * nh.y, z))
        }

        /// A direction wi for wo: the specular lobe's reflection about a
        /// visible normal with `specular_probability`, decided by u_lobe,
        /// else the diffuse lobe's cosine-distributed one; weight =
        /// bsdf_eval/bsdf_pdf there (the mixture's pdf, so either lobe's
        /// sample counts both).
        #[inline(always)]
        pub fn bsdf_sample(p: BsdfParams, wo: Vec3, u: Vec2, u_lobe: Real) -> BsdfSample {
            let none = BsdfSample {
                wi: Vec3::ZERO,
                weight: Vec3::ZERO,
                pdf: 0.0,
                ok: false,
            };
            if wo.z <= 0.0 {
                return none;
            }
            let wi = if p.kind != crate::layout::MATERIAL_LAMBERT
                && u_lobe < specular_probability(p, wo.z)
            {
                let h = sample_ggx_visible_normal(wo, ggx_alpha(p.roughness), u);
                h * (2.0 * dot3(wo, h)) - wo
            } else {
                sample_cosine(u)
            };
            let pdf = bsdf_pdf(p, wo, wi);
            if pdf <= 0.0 {
                return none;
            }
            BsdfSample {
                wi,
                weight: bsdf_eval(p, wo, wi) / pdf,
                pdf,
                ok: true,
            }
        }
    };
}
pub(crate) use bsdf;
