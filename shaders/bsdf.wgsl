// Stage: BSDF. Lambert (albedo/π) and glTF 2.0's metallic-roughness BRDF
// (its specification's appendix B: Trowbridge-Reitz/GGX D with α =
// roughness², the height-correlated Smith visibility, Schlick's Fresnel
// with F0 = 0.04 for the dielectric and the base colour for the metal,
// mix(dielectric, metal, metallic)), its specular lobe sampled by visible
// normals (Heitz 2018), and the shading frame (Duff et al. 2017). All in
// the local frame: z the shading normal, wo towards the viewer, wi towards
// the light, both unit and pointing away from the surface; a direction
// below the shading horizon gives 0 (the caller checks the geometric one).
// Every product that feeds a sum is `rounded` (as in math.wgsl), so that
// the CPU twin (src/cpu/bsdf.rs) computes the same bits. Formulas and
// references in docs/rendering.md ("The BSDF").

// A floor on GGX's α: a smooth surface (roughness 0) is a lobe about a
// milliradian wide, not a delta the integrator would need a case for; D
// peaks at 1/(π α²) = 3.2e5, well within f32.
const ALPHA_MIN: f32 = 0.001f;
// The dielectric's reflectance at normal incidence (glTF: IOR 1.5).
const DIELECTRIC_F0: f32 = 0.04f;
// Where both lobes reflect, each is chosen at least this often, which
// bounds f·cos/pdf by 1/LOBE_PROBABILITY_MIN (docs/rendering.md).
const LOBE_PROBABILITY_MIN: f32 = 0.1f;

struct BsdfParams {
    base_color: vec3<f32>,
    metallic: f32,
    roughness: f32,
    kind: u32,
}

// A sampled direction: weight = f·|cos θi|/pdf; ok false where none was
// made (wo below the horizon, or a reflection below it).
struct BsdfSample {
    wi: vec3<f32>,
    weight: vec3<f32>,
    pdf: f32,
    ok: bool,
}

// An orthonormal frame (tangent, bitangent, n) about unit n, as columns:
// Duff et al., "Building an Orthonormal Basis, Revisited" (JCGT 2017).
fn frame_from_normal(n: vec3<f32>) -> mat3x3<f32> {
    let sign = select(1.0, -1.0, n.z < 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let tangent = vec3<f32>(1.0 + rounded(sign * n.x * n.x * a), sign * b, -sign * n.x);
    let bitangent = vec3<f32>(b, sign + rounded(n.y * n.y * a), -n.y);
    return mat3x3<f32>(tangent, bitangent, n);
}

fn to_local(frame: mat3x3<f32>, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot3(frame[0], v), dot3(frame[1], v), dot3(frame[2], v));
}

fn to_world(frame: mat3x3<f32>, v: vec3<f32>) -> vec3<f32> {
    return rounded3(frame[0] * v.x) + rounded3(frame[1] * v.y) + rounded3(frame[2] * v.z);
}

// GGX's α for a perceptual roughness (glTF: α = roughness²), floored.
fn ggx_alpha(roughness: f32) -> f32 {
    return max(roughness * roughness, ALPHA_MIN);
}

fn ggx_alpha2(roughness: f32) -> f32 {
    let alpha = ggx_alpha(roughness);
    return alpha * alpha;
}

// Trowbridge-Reitz D(h) for unit h above the surface, its denominator
// sin²θ + α²cos²θ from h's components: (n·h)²(α² − 1) + 1 would cancel
// to nothing in f32 near the peak of a sharp lobe.
fn ggx_d(h: vec3<f32>, alpha2: f32) -> f32 {
    let t = rounded(h.x * h.x) + rounded(h.y * h.y) + rounded(alpha2 * rounded(h.z * h.z));
    return alpha2 / (PI * t * t);
}

// √(cos²θ + α² sin²θ) of unit w: Smith's Λ(w) = (√(1 + α² tan²θ) − 1)/2
// is this over cos θ, less one, halved.
fn smith_root(w: vec3<f32>, alpha2: f32) -> f32 {
    let sin2 = rounded(w.x * w.x) + rounded(w.y * w.y);
    return safe_sqrt(rounded(w.z * w.z) + rounded(alpha2 * sin2));
}

// Schlick's (1 − cos)⁵.
fn schlick_weight(cos_theta: f32) -> f32 {
    return approx_pow5(1.0 - max(cos_theta, 0.0));
}

fn mean3(c: vec3<f32>) -> f32 {
    return (c.x + c.y + c.z) / 3.0;
}

// The metallic-roughness BRDF f(wo, wi), both above the surface: glTF 2.0
// appendix B's formulas in its order.
fn metallic_roughness_f(p: BsdfParams, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let alpha2 = ggx_alpha2(p.roughness);
    let h = normalize3(wo + wi);
    let w5 = schlick_weight(dot3(wo, h));
    // V·D, V the height-correlated Smith visibility G2/(4 cos θo cos θi).
    let visibility = 0.5
        / (rounded(wi.z * smith_root(wo, alpha2)) + rounded(wo.z * smith_root(wi, alpha2)));
    let specular = visibility * ggx_d(h, alpha2);
    let f_dielectric = DIELECTRIC_F0 + rounded((1.0 - DIELECTRIC_F0) * w5);
    let f_metal = p.base_color + rounded3((1.0 - p.base_color) * w5);
    let dielectric = rounded3(p.base_color * INV_PI * (1.0 - f_dielectric))
        + rounded(specular * f_dielectric);
    return rounded3(dielectric * (1.0 - p.metallic)) + rounded3(f_metal * specular * p.metallic);
}

// f(wo, wi)·cos θi in the local frame; 0 unless both are above the surface.
fn bsdf_eval(p: BsdfParams, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return vec3<f32>(0.0);
    }
    if p.kind == MATERIAL_LAMBERT {
        return p.base_color * (INV_PI * wi.z);
    }
    return metallic_roughness_f(p, wo, wi) * wi.z;
}

// The probability of sampling the specular lobe for wo: the lobes'
// reflectances estimated with cos θo for the half vector's cosine (colours
// by their mean), kept in [LOBE_PROBABILITY_MIN, 1 − that] where both
// reflect; 1 where the diffuse lobe is black (a metal, a black base).
fn specular_probability(p: BsdfParams, cos_o: f32) -> f32 {
    let w5 = schlick_weight(cos_o);
    let f0 = rounded(DIELECTRIC_F0 * (1.0 - p.metallic))
        + rounded(mean3(p.base_color) * p.metallic);
    let specular = f0 + rounded((1.0 - f0) * w5);
    let f_dielectric = DIELECTRIC_F0 + rounded((1.0 - DIELECTRIC_F0) * w5);
    let diffuse = (1.0 - p.metallic) * (1.0 - f_dielectric) * mean3(p.base_color);
    if diffuse <= 0.0 {
        return 1.0;
    }
    return clamp(specular / (specular + diffuse), LOBE_PROBABILITY_MIN, 1.0 - LOBE_PROBABILITY_MIN);
}

// The solid-angle pdf of `bsdf_sample` at wi; 0 unless both are above the
// surface. The specular lobe's: D(h)·G1(wo)/(4 cos θo) (Heitz 2018, eq. 17
// with the reflection's Jacobian 1/(4 wo·h)), G1(wo) = 2 cos θo/(cos θo +
// smith_root(wo)).
fn bsdf_pdf(p: BsdfParams, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let diffuse = wi.z * INV_PI;
    if p.kind == MATERIAL_LAMBERT {
        return diffuse;
    }
    let alpha2 = ggx_alpha2(p.roughness);
    let h = normalize3(wo + wi);
    let specular = ggx_d(h, alpha2) / (2.0 * (wo.z + smith_root(wo, alpha2)));
    let q = specular_probability(p, wo.z);
    return rounded(q * specular) + rounded((1.0 - q) * diffuse);
}

// A cosine-distributed direction about z (pdf cos θ/π), by polar
// coordinates on the unit disc.
fn sample_cosine(u: vec2<f32>) -> vec3<f32> {
    let sc = approx_sin_cos(TWO_PI * u.y);
    let r = sqrt(u.x);
    return vec3<f32>(r * sc.y, r * sc.x, safe_sqrt(1.0 - u.x));
}

// A microfacet normal distributed as GGX's visible normals seen from wo:
// Heitz, "Sampling the GGX Distribution of Visible Normals" (JCGT 2018),
// listing 1, isotropic, with T2 = Vh × T1 written out and the lift off
// the disc computed without cancellation.
fn sample_ggx_visible_normal(wo: vec3<f32>, alpha: f32, u: vec2<f32>) -> vec3<f32> {
    // The view direction stretched to the hemisphere configuration.
    let vh = normalize3(vec3<f32>(alpha * wo.x, alpha * wo.y, wo.z));
    let length2 = rounded(vh.x * vh.x) + rounded(vh.y * vh.y);
    let length = safe_sqrt(length2);
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if length2 > 0.0 {
        t1 = vec3<f32>(-vh.y, vh.x, 0.0) * (1.0 / length);
    }
    let t2 = vec3<f32>(-vh.z * t1.y, vh.z * t1.x, length);
    // A point on the disc, warped to the visible half of the hemisphere's
    // projection, then lifted onto the hemisphere.
    let sc = approx_sin_cos(TWO_PI * u.y);
    let r = sqrt(u.x);
    let d1 = r * sc.y;
    let t2_disc = r * sc.x;
    let s = 0.5 * (1.0 + vh.z);
    let q = safe_sqrt(1.0 - rounded(d1 * d1));
    let d2 = rounded((1.0 - s) * q) + rounded(s * t2_disc);
    // √(1 − d1² − d2²) cancels to noise at the disc's rim in f32. It is
    // (q − d2)(q + d2) = s a · (2(1 − s) q + s b), a = q − t2_disc,
    // b = q + t2_disc, a b = 1 − r² = 1 − u.x: the one of a and b that
    // does not cancel directly, the other as 1 − u.x over it.
    var a = q - t2_disc;
    var b = q + t2_disc;
    if t2_disc < 0.0 {
        b = (1.0 - u.x) / a;
    } else {
        a = (1.0 - u.x) / b;
    }
    let lift = safe_sqrt(s * a * (rounded(2.0 * (1.0 - s) * q) + rounded(s * b)));
    let nh = rounded3(d1 * t1) + rounded3(d2 * t2) + rounded3(lift * vh);
    // Back to the ellipsoid configuration.
    return normalize3(vec3<f32>(alpha * nh.x, alpha * nh.y, select(nh.z, 0.0, nh.z < 0.0)));
}

// A direction wi for wo: the specular lobe's reflection about a visible
// normal with `specular_probability`, decided by u_lobe, else the diffuse
// lobe's cosine-distributed one; weight = bsdf_eval/bsdf_pdf there (the
// mixture's pdf, so either lobe's sample counts both).
fn bsdf_sample(p: BsdfParams, wo: vec3<f32>, u: vec2<f32>, u_lobe: f32) -> BsdfSample {
    let none = BsdfSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, false);
    if wo.z <= 0.0 {
        return none;
    }
    var wi: vec3<f32>;
    if p.kind != MATERIAL_LAMBERT && u_lobe < specular_probability(p, wo.z) {
        let h = sample_ggx_visible_normal(wo, ggx_alpha(p.roughness), u);
        wi = rounded3((2.0 * dot3(wo, h)) * h) - wo;
    } else {
        wi = sample_cosine(u);
    }
    let pdf = bsdf_pdf(p, wo, wi);
    if pdf <= 0.0 {
        return none;
    }
    return BsdfSample(wi, bsdf_eval(p, wo, wi) / pdf, pdf, true);
}
