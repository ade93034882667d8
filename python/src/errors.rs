//! The exceptions the extension raises: lambert's own classes
//! (python/lambert/_errors.py), each also the built-in a Python user
//! expects (`LambertValueError` is a `ValueError`, ...).

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyType;

/// Which of lambert's exception classes.
#[derive(Clone, Copy)]
pub enum Kind {
    Value,
    Os,
    FileNotFound,
    Permission,
    Runtime,
}

impl Kind {
    fn class_name(self) -> &'static str {
        match self {
            Kind::Value => "LambertValueError",
            Kind::Os => "LambertOSError",
            Kind::FileNotFound => "LambertFileNotFoundError",
            Kind::Permission => "LambertPermissionError",
            Kind::Runtime => "LambertRuntimeError",
        }
    }
}

/// An exception of lambert's class `kind` with `message`.
pub fn error(kind: Kind, message: impl Into<String>) -> PyErr {
    let message = message.into();
    Python::attach(|py| {
        let class = py
            .import("lambert._errors")
            .and_then(|m| m.getattr(kind.class_name()))
            .and_then(|c| c.cast_into::<PyType>().map_err(PyErr::from));
        match class {
            Ok(class) => PyErr::from_type(class, message),
            // The package's module is missing only where the extension is
            // imported without it: the built-in still says what went wrong.
            Err(_) => PyRuntimeError::new_err(message),
        }
    })
}

/// A bad value: `LambertValueError`, a `ValueError`.
pub fn value_error(message: impl Into<String>) -> PyErr {
    error(Kind::Value, message)
}
