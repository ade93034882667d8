//! STAND-IN (the lead's scratch, replaced by the BSDF engineer's at merge).
macro_rules! bsdf {
    () => {
        pub struct BsdfParams { pub base_color: Vec3, pub metallic: Real, pub roughness: Real, pub kind: u32 }
        pub struct BsdfSample { pub wi: Vec3, pub weight: Vec3, pub pdf: Real, pub ok: bool }
        pub struct Frame { pub t: Vec3, pub b: Vec3, pub n: Vec3 }
        impl Frame {
            pub fn to_local(&self, v: Vec3) -> Vec3 { Vec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n)) }
            pub fn to_world(&self, v: Vec3) -> Vec3 { self.t * v.x + self.b * v.y + self.n * v.z }
        }
        pub fn frame_from_normal(n: Vec3) -> Frame {
            let sign: Real = if n.z >= 0.0 { 1.0 } else { -1.0 };
            let a = -1.0 / (sign + n.z);
            let b = n.x * n.y * a;
            Frame { t: Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), b: Vec3::new(b, sign + n.y * n.y * a, -n.y), n }
        }
        pub fn bsdf_eval(p: &BsdfParams, wo: Vec3, wi: Vec3) -> Vec3 {
            if wo.z <= 0.0 || wi.z <= 0.0 { return Vec3::ZERO; }
            p.base_color * (wi.z / std::f64::consts::PI as Real)
        }
        pub fn bsdf_pdf(_p: &BsdfParams, wo: Vec3, wi: Vec3) -> Real {
            if wo.z <= 0.0 || wi.z <= 0.0 { return 0.0; }
            wi.z / std::f64::consts::PI as Real
        }
        pub fn bsdf_sample(p: &BsdfParams, wo: Vec3, u: Vec2, _u_lobe: Real) -> BsdfSample {
            let r = u.x.sqrt();
            let phi = 2.0 * std::f64::consts::PI as Real * u.y;
            let wi = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u.x).max(0.0).sqrt());
            let pdf = wi.z / std::f64::consts::PI as Real;
            BsdfSample { wi, weight: p.base_color, pdf, ok: wo.z > 0.0 && pdf > 0.0 }
        }
    };
}
pub(crate) use bsdf;
