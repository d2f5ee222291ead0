//! The Python exception tree and the one exhaustive mapping from core errors to it.
//!
//! ```text
//! MmusvError(Exception)
//! ├── InputError        bad array shape / dtype / value
//! ├── GeometryError     unusable mesh data
//! ├── ConfigError       scenario / route / speed / wave values
//! ├── NotFoundError     unknown mesh or instance id
//! ├── IoError           file could not be read or written
//! └── InternalError     a bug in mmusv (a caught panic)
//! ```

use mmusv_core::MmusvError as CoreError;
use pyo3::create_exception;
use pyo3::prelude::*;

create_exception!(mmusv._core, MmusvError, pyo3::exceptions::PyException, "Base class of every mmusv error.");
create_exception!(mmusv._core, InputError, MmusvError, "An argument has the wrong shape, dtype or value.");
create_exception!(mmusv._core, GeometryError, MmusvError, "Mesh data that cannot be used (empty, NaN, bad indices).");
create_exception!(mmusv._core, ConfigError, MmusvError, "A configuration value outside what is allowed.");
create_exception!(mmusv._core, NotFoundError, MmusvError, "An id, asset or name that does not exist.");
create_exception!(mmusv._core, IoError, MmusvError, "A file could not be read or written.");
create_exception!(mmusv._core, InternalError, MmusvError, "A bug in mmusv (an internal panic was caught).");

/// Maps a core error to its Python exception. Exhaustive: a new core variant fails to compile here.
pub fn to_py(err: CoreError) -> PyErr {
    let msg = err.to_string();
    match err {
        CoreError::InvalidInput { .. } => InputError::new_err(msg),
        CoreError::Geometry { .. } => GeometryError::new_err(msg),
        CoreError::Config { .. } => ConfigError::new_err(msg),
        CoreError::UnknownId { .. } => NotFoundError::new_err(msg),
        CoreError::Io { .. } => IoError::new_err(msg),
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("MmusvError", py.get_type::<MmusvError>())?;
    m.add("InputError", py.get_type::<InputError>())?;
    m.add("GeometryError", py.get_type::<GeometryError>())?;
    m.add("ConfigError", py.get_type::<ConfigError>())?;
    m.add("NotFoundError", py.get_type::<NotFoundError>())?;
    m.add("IoError", py.get_type::<IoError>())?;
    m.add("InternalError", py.get_type::<InternalError>())?;
    Ok(())
}
