//! The .msh reader (being written; see issue 2).

use crate::{Mesh, MeshError, MeshErrorKind};

pub(crate) fn read(_bytes: &[u8]) -> Result<Mesh, MeshError> {
    Err(MeshError::new(MeshErrorKind::Io("the .msh reader is not written yet".into())))
}
