//! The one place where core errors become Python exceptions.

use pyo3::PyErr;
use pyo3::exceptions::{PyException, PyKeyboardInterrupt, PyMemoryError, PyValueError};

pyo3::create_exception!(
    skyfall,
    SkyfallError,
    PyException,
    "Base of skyfall's own exceptions (bad values raise ValueError, bad types TypeError)."
);

pyo3::create_exception!(
    skyfall,
    GpuUnavailableError,
    SkyfallError,
    "No usable GPU adapter (or none of the kind asked for); the message says what to install."
);

/// Maps a GPU-backend error: missing adapters to GpuUnavailableError, bad input to
/// ValueError, device failures to SkyfallError.
pub fn gpu_error(e: skyfall_gpu::GpuError) -> PyErr {
    use skyfall_gpu::GpuError as G;
    match e {
        G::NoAdapter { .. } | G::NoHardwareAdapter { .. } | G::Device(_) => {
            GpuUnavailableError::new_err(e.to_string())
        }
        G::TooLarge { .. } => PyValueError::new_err(e.to_string()),
        G::Core(c) => CoreError(c).into(),
        G::Wgpu(_) | G::Readback(_) => SkyfallError::new_err(e.to_string()),
    }
}

/// A value refused for a reason other than its range (a shape, a missing partner argument):
/// the core's [`skyfall_core::Error::Invalid`], through the one mapping.
pub fn invalid(name: &'static str, index: Option<usize>, message: impl Into<String>) -> PyErr {
    CoreError(skyfall_core::Error::Invalid {
        param: skyfall_core::error::Param { name, index },
        message: message.into(),
    })
    .into()
}

/// An `out=` array numpy will not lend for writing (an input of the same render, or in use
/// by another): the one refusal that is about Python objects rather than values.
/// `what` names the array as the caller knows it (`out rgb`, `rain_alpha_out`).
pub fn in_use(what: &str) -> PyErr {
    PyValueError::new_err(format!(
        "{what} is in use elsewhere (an input of this render, or another render, perhaps on another thread): pass a separate array"
    ))
}

/// A core error on its way to Python.
pub struct CoreError(pub skyfall_core::Error);

impl From<skyfall_core::Error> for CoreError {
    fn from(e: skyfall_core::Error) -> Self {
        CoreError(e)
    }
}

impl From<CoreError> for PyErr {
    fn from(e: CoreError) -> PyErr {
        use skyfall_core::Error as E;
        match e.0 {
            // A value the caller passed.
            err @ (E::OutOfRange { .. }
            | E::Invalid { .. }
            | E::Unusable { .. }
            | E::TooLarge { .. }
            | E::Length { .. }) => PyValueError::new_err(err.to_string()),
            err @ E::OutOfMemory { .. } => PyMemoryError::new_err(err.to_string()),
            // Cancelled work ends with the exception the signal handler raised (see
            // `crate::interrupt`); this is the fallback should none be pending.
            err @ E::Cancelled { .. } => PyKeyboardInterrupt::new_err(err.to_string()),
        }
    }
}
