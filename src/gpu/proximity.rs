//! Geometric queries on the resident scene (closest points, winding
//! numbers, every hit along rays): points and rays in the scene's local
//! frame, answers in it (`proximity`, in the engine, moves them).

use crate::error::{Error, Result};
use crate::layout::{ClosestPoint, ListedHit, Ray};

use super::GpuRenderer;

impl GpuRenderer {
    /// Spheres in the resident scene (the queries are over triangles).
    pub fn sphere_count(&self) -> u32 {
        self.params.num_spheres
    }

    fn not_on_gpu<T>(&self, query: &str) -> Result<T> {
        Err(Error::Gpu(format!(
            "{query} are not yet computed on the GPU path: use the CPU path (device \"cpu\")"
        )))
    }

    pub fn closest_points(&mut self, _points: &[[f32; 3]], _max: f32) -> Result<Vec<ClosestPoint>> {
        self.not_on_gpu("closest points")
    }

    pub fn winding_numbers(&mut self, _points: &[[f32; 3]]) -> Result<Vec<f32>> {
        self.not_on_gpu("winding numbers")
    }

    pub fn count_intersections(&mut self, _rays: &[Ray]) -> Result<Vec<u32>> {
        self.not_on_gpu("intersection counts")
    }

    pub fn list_intersections(&mut self, _rays: &[Ray]) -> Result<(Vec<u64>, Vec<ListedHit>)> {
        self.not_on_gpu("intersection lists")
    }
}
