//! Reading numpy arrays as they are laid out: any strides (C or Fortran
//! order, transposed, reversed, sliced, broadcast), float32 or float64.
//! Only C-ordered rows are read as one packed slice (numpy calls an array
//! "contiguous" in either order, so contiguity alone says nothing about
//! where row i lies); every other layout is read through its strides.

use numpy::ndarray::{ArrayView1, ArrayView2, Dimension, Ix1, Ix2};
use numpy::{PyReadonlyArray, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// A float array of either width, as numpy gave it (any strides).
pub enum Floats<'py, D: Dimension> {
    F32(PyReadonlyArray<'py, f32, D>),
    F64(PyReadonlyArray<'py, f64, D>),
}

impl<'py, D: Dimension> Floats<'py, D> {
    /// `value` as a float32 array, else as a float64 one; None if it is
    /// neither.
    fn from_any(value: &Bound<'py, PyAny>) -> Option<Floats<'py, D>> {
        match value.extract() {
            Ok(a) => Some(Floats::F32(a)),
            Err(_) => value.extract().ok().map(Floats::F64),
        }
    }

    fn shape(&self) -> &[usize] {
        match self {
            Floats::F32(a) => a.shape(),
            Floats::F64(a) => a.shape(),
        }
    }
}

/// A (N, 3) float array of either width.
pub type Rows<'py> = Floats<'py, Ix2>;

impl<'py> Rows<'py> {
    pub fn extract(name: &str, value: &Bound<'py, PyAny>) -> PyResult<Rows<'py>> {
        let rows = Floats::from_any(value).ok_or_else(|| {
            PyValueError::new_err(format!("{name} must be a (N, 3) float32 or float64 array"))
        })?;
        let shape = rows.shape();
        if shape[1] != 3 {
            return Err(PyValueError::new_err(format!(
                "{name} has shape {shape:?}; it must be (N, 3)"
            )));
        }
        Ok(rows)
    }

    pub fn len(&self) -> usize {
        self.shape()[0]
    }

    pub fn view(&self) -> RowsView<'_> {
        match self {
            Rows::F32(a) => {
                packed(a).map_or_else(|| RowsView::F32(a.as_array()), RowsView::PackedF32)
            }
            Rows::F64(a) => {
                packed(a).map_or_else(|| RowsView::F64(a.as_array()), RowsView::PackedF64)
            }
        }
    }
}

/// The array's elements as one slice, row after row, if it is C-ordered.
fn packed<'a, T: numpy::Element>(a: &'a PyReadonlyArray2<'_, T>) -> Option<&'a [T]> {
    if a.is_c_contiguous() {
        a.as_slice().ok()
    } else {
        None
    }
}

/// `Rows` as a view the tracing threads can share: packed C-ordered rows
/// (the usual case) read as slices, others through their strides.
#[derive(Clone, Copy)]
pub enum RowsView<'a> {
    PackedF32(&'a [f32]),
    PackedF64(&'a [f64]),
    F32(ArrayView2<'a, f32>),
    F64(ArrayView2<'a, f64>),
}

impl RowsView<'_> {
    /// Row `i` as given (float32 widened exactly): an origin stays in f64
    /// until it becomes a ray.
    #[inline]
    pub fn row_f64(&self, i: usize) -> [f64; 3] {
        match self {
            RowsView::PackedF32(a) => [a[3 * i], a[3 * i + 1], a[3 * i + 2]].map(f64::from),
            RowsView::PackedF64(a) => [a[3 * i], a[3 * i + 1], a[3 * i + 2]],
            RowsView::F32(a) => [a[[i, 0]], a[[i, 1]], a[[i, 2]]].map(f64::from),
            RowsView::F64(a) => [a[[i, 0]], a[[i, 1]], a[[i, 2]]],
        }
    }

    /// Whether its values are float64.
    pub fn is_f64(&self) -> bool {
        matches!(self, RowsView::PackedF64(_) | RowsView::F64(_))
    }

    /// Row `i` in float32, as a ray holds it.
    #[inline]
    pub fn row(&self, i: usize) -> [f32; 3] {
        self.row_f64(i).map(|c| c as f32)
    }
}

/// tmin or tmax: one value for every ray, or one each (float32, or
/// float64 kept in f64 for rays traced in the scene's frame).
pub enum Bound1<'py> {
    All(f64),
    Each(Floats<'py, Ix1>),
}

impl<'py> Bound1<'py> {
    pub fn extract(name: &str, value: &Bound<'py, PyAny>, n: usize) -> PyResult<Bound1<'py>> {
        let Some(each) = Floats::from_any(value) else {
            return match value.extract::<f64>() {
                Ok(v) => Ok(Bound1::All(v)),
                Err(_) => Err(PyValueError::new_err(format!(
                    "{name} must be a number or a (N,) float32 or float64 array"
                ))),
            };
        };
        let len = each.shape()[0];
        if len != n {
            return Err(PyValueError::new_err(format!(
                "{name} has {len} values for {n} rays; give one per ray or a scalar"
            )));
        }
        Ok(Bound1::Each(each))
    }

    pub fn view(&self) -> Bound1View<'_> {
        match self {
            Bound1::All(v) => Bound1View::All(*v),
            Bound1::Each(Floats::F32(a)) => Bound1View::Each32(a.as_array()),
            Bound1::Each(Floats::F64(a)) => Bound1View::Each64(a.as_array()),
        }
    }
}

#[derive(Clone, Copy)]
pub enum Bound1View<'a> {
    All(f64),
    Each32(ArrayView1<'a, f32>),
    Each64(ArrayView1<'a, f64>),
}

impl Bound1View<'_> {
    /// Ray `i`'s value as given (float32 widened exactly).
    #[inline]
    pub fn at(&self, i: usize) -> f64 {
        match self {
            Bound1View::All(v) => *v,
            Bound1View::Each32(a) => a[i] as f64,
            Bound1View::Each64(a) => a[i],
        }
    }
}

/// The rows of a (N, 3) array, by its strides.
pub fn rows3<T: numpy::Element + Copy>(a: &PyReadonlyArray2<'_, T>) -> Vec<[T; 3]> {
    a.as_array()
        .rows()
        .into_iter()
        .map(|r| [r[0], r[1], r[2]])
        .collect()
}
