//! STAND-IN (the lead's scratch, replaced by the lights engineer's at merge).
macro_rules! lights {
    () => {
        pub struct EmitterSample { pub wi: Vec3, pub distance: Real, pub radiance: Vec3, pub pdf: Real, pub delta: bool }
        impl<'a> Kernel<'a> {
            pub fn has_environment(&self) -> bool { false }
            pub fn has_emitters(&self) -> bool { false }
            pub fn sample_emitter(&self, _p: Vec3, _n: Vec3, _u_pick: Real, _u: Vec2) -> EmitterSample {
                EmitterSample { wi: Vec3::Z, distance: FAR, radiance: Vec3::ZERO, pdf: 0.0, delta: false }
            }
            pub fn emitter_pdf(&self, _p: Vec3, _prim: u32, _wi: Vec3, _t: Real) -> Real { 0.0 }
            pub fn environment_radiance(&self, _d: Vec3) -> Vec3 { Vec3::ZERO }
            pub fn environment_pdf(&self, _d: Vec3) -> Real { 0.0 }
        }
    };
}
pub(crate) use lights;
