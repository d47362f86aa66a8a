//! Buffers and accessors: resolving `data:` URIs, external files and the GLB blob, and reading
//! accessors with every length checked before anything is allocated.

use std::path::{Path, PathBuf};

use gltf::Accessor;
use gltf::accessor::{DataType, Dimensions};

use crate::error::{Result, SceneError};
use crate::util::{base64_decode, percent_decode};

/// The most elements an accessor without a buffer view (all zeros, sparse) may declare.
const MAX_IMPLICIT_COUNT: usize = 1 << 22;

/// What an accessor's data is read for: the file name travels with every error.
pub(super) struct Data<'a> {
    pub(super) file: &'a str,
    pub(super) base_dir: Option<&'a Path>,
    pub(super) buffers: Vec<Vec<u8>>,
}

impl<'a> Data<'a> {
    pub(super) fn err(&self, element: impl Into<String>, problem: impl Into<String>) -> SceneError {
        SceneError::invalid(self.file, element, problem)
    }

    /// Loads every buffer of the document: the GLB blob, `data:` URIs and external files.
    pub(super) fn load(
        file: &'a str,
        base_dir: Option<&'a Path>,
        document: &gltf::Document,
        mut blob: Option<Vec<u8>>,
    ) -> Result<Self> {
        let mut data = Self {
            file,
            base_dir,
            buffers: Vec::new(),
        };
        for buffer in document.buffers() {
            let element = format!("buffer {}", buffer.index());
            let bytes = match buffer.source() {
                gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                    data.err(&element, "refers to a GLB binary chunk the file lacks")
                })?,
                gltf::buffer::Source::Uri(uri) => data.resolve_uri(&element, uri)?,
            };
            if bytes.len() < buffer.length() {
                return Err(data.err(
                    element,
                    format!(
                        "byteLength is {} but only {} bytes of data",
                        buffer.length(),
                        bytes.len()
                    ),
                ));
            }
            data.buffers.push(bytes);
        }
        Ok(data)
    }

    /// The bytes of a `data:` URI or of a file relative to the glTF file.
    pub(super) fn resolve_uri(&self, element: &str, uri: &str) -> Result<Vec<u8>> {
        if let Some(rest) = uri.strip_prefix("data:") {
            let (header, payload) = rest
                .split_once(',')
                .ok_or_else(|| self.err(element, "malformed data: URI (no comma)"))?;
            if !header.ends_with(";base64") {
                return Err(self.err(element, "data: URI is not base64"));
            }
            return base64_decode(payload)
                .map_err(|e| self.err(element, format!("data: URI: {e}")));
        }
        if uri.contains("://") {
            return Err(self.err(
                element,
                format!("external URI {uri:?} is not a relative file path"),
            ));
        }
        let Some(base_dir) = self.base_dir else {
            return Err(self.err(
                element,
                format!("refers to file {uri:?} but the data has no directory"),
            ));
        };
        let path: PathBuf = base_dir.join(percent_decode(uri));
        std::fs::read(&path).map_err(|source| SceneError::Resource {
            file: self.file.to_owned(),
            element: element.to_owned(),
            path,
            source,
        })
    }

    /// The bytes of buffer view `view`, checked against its buffer.
    pub(super) fn view_bytes(&self, view: &gltf::buffer::View) -> Result<&[u8]> {
        let element = format!("bufferView {}", view.index());
        let buffer = &self.buffers[view.buffer().index()];
        let end = view
            .offset()
            .checked_add(view.length())
            .filter(|&end| end <= buffer.len())
            .ok_or_else(|| {
                self.err(
                    &element,
                    format!(
                        "byteOffset {} + byteLength {} exceeds buffer {} of {} bytes",
                        view.offset(),
                        view.length(),
                        view.buffer().index(),
                        buffer.len()
                    ),
                )
            })?;
        Ok(&buffer[view.offset()..end])
    }

    /// Reads an accessor as `f32` components, `components` per element. Float accessors are
    /// read as they are; normalised integer accessors only when `normalized_ok`.
    pub(super) fn read_floats(
        &self,
        accessor: &Accessor,
        dims: Dimensions,
        normalized_ok: bool,
        what: &str,
    ) -> Result<Vec<f32>> {
        let element = format!("accessor {}", accessor.index());
        if accessor.dimensions() != dims {
            return Err(self.err(
                element,
                format!("{what} must be {dims:?}, found {:?}", accessor.dimensions()),
            ));
        }
        let ty = accessor.data_type();
        let convert: fn(&[u8]) -> f32 = match ty {
            DataType::F32 => |b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            _ if !(normalized_ok && accessor.normalized()) => {
                return Err(self.err(
                    element,
                    format!(
                        "unsupported component type {ty:?}{} for {what}",
                        if accessor.normalized() {
                            " (normalized)"
                        } else {
                            ""
                        }
                    ),
                ));
            }
            DataType::I8 => |b| (f32::from(b[0] as i8) / 127.0).max(-1.0),
            DataType::U8 => |b| f32::from(b[0]) / 255.0,
            DataType::I16 => |b| (f32::from(i16::from_le_bytes([b[0], b[1]])) / 32767.0).max(-1.0),
            DataType::U16 => |b| f32::from(u16::from_le_bytes([b[0], b[1]])) / 65535.0,
            DataType::U32 => {
                return Err(self.err(
                    element,
                    format!("unsupported component type U32 for {what}"),
                ));
            }
        };
        let values = self.read_elements(accessor, convert)?;
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(self.err(
                element,
                format!(
                    "{what}: non-finite value at element {}",
                    i / dims.multiplicity()
                ),
            ));
        }
        Ok(values)
    }

    /// Reads a scalar integer accessor (vertex indices).
    pub(super) fn read_indices(&self, accessor: &Accessor) -> Result<Vec<u32>> {
        let element = format!("accessor {}", accessor.index());
        if accessor.dimensions() != Dimensions::Scalar {
            return Err(self.err(
                element,
                format!("indices must be Scalar, found {:?}", accessor.dimensions()),
            ));
        }
        let convert: fn(&[u8]) -> u32 = match accessor.data_type() {
            DataType::U8 => |b| u32::from(b[0]),
            DataType::U16 => |b| u32::from(u16::from_le_bytes([b[0], b[1]])),
            DataType::U32 => |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            other => {
                return Err(self.err(
                    element,
                    format!("unsupported component type {other:?} for indices"),
                ));
            }
        };
        self.read_elements(accessor, convert)
    }

    /// Reads every component of `accessor` with `convert`, applying sparse substitution.
    fn read_elements<T: Copy + Default>(
        &self,
        accessor: &Accessor,
        convert: fn(&[u8]) -> T,
    ) -> Result<Vec<T>> {
        let element = format!("accessor {}", accessor.index());
        let count = accessor.count();
        let comp_size = accessor.data_type().size();
        let comps = accessor.dimensions().multiplicity();
        if matches!(
            accessor.dimensions(),
            Dimensions::Mat2 | Dimensions::Mat3 | Dimensions::Mat4
        ) {
            return Err(self.err(element, "matrix accessors are not supported here"));
        }
        let elem_size = comp_size * comps;
        let mut out = match accessor.view() {
            Some(view) => {
                let bytes = self.view_bytes(&view)?;
                let stride = view.stride().unwrap_or(elem_size);
                if stride < elem_size {
                    return Err(self.err(
                        element,
                        format!("byteStride {stride} smaller than element size {elem_size}"),
                    ));
                }
                let needed = if count == 0 {
                    Some(0)
                } else {
                    (count - 1)
                        .checked_mul(stride)
                        .and_then(|n| n.checked_add(elem_size))
                        .and_then(|n| n.checked_add(accessor.offset()))
                };
                match needed {
                    Some(n) if n <= bytes.len() => {}
                    _ => {
                        return Err(self.err(
                            element,
                            format!(
                                "{count} elements of {elem_size} bytes (stride {stride}, offset {}) exceed bufferView {} of {} bytes",
                                accessor.offset(),
                                view.index(),
                                bytes.len()
                            ),
                        ));
                    }
                }
                let mut out = Vec::with_capacity(count * comps);
                for i in 0..count {
                    let start = accessor.offset() + i * stride;
                    for c in 0..comps {
                        let at = start + c * comp_size;
                        out.push(convert(&bytes[at..at + comp_size]));
                    }
                }
                out
            }
            None if accessor.sparse().is_some() && count <= MAX_IMPLICIT_COUNT => {
                vec![T::default(); count * comps]
            }
            None if accessor.sparse().is_some() => {
                return Err(self.err(
                    element,
                    format!("count {count} without a bufferView is too large"),
                ));
            }
            None => return Err(self.err(element, "has neither a bufferView nor sparse data")),
        };
        if let Some(sparse) = accessor.sparse() {
            let n = sparse.count();
            let indices = sparse.indices();
            let index_size = match indices.index_type() {
                gltf::accessor::sparse::IndexType::U8 => 1,
                gltf::accessor::sparse::IndexType::U16 => 2,
                gltf::accessor::sparse::IndexType::U32 => 4,
            };
            let index_bytes = self.view_bytes(&indices.view())?;
            let value_bytes = self.view_bytes(&sparse.values().view())?;
            let fits = |offset: usize, size: usize, len: usize| {
                n.checked_mul(size)
                    .and_then(|b| b.checked_add(offset))
                    .is_some_and(|end| end <= len)
            };
            if !fits(indices.offset(), index_size, index_bytes.len())
                || !fits(sparse.values().offset(), elem_size, value_bytes.len())
            {
                return Err(self.err(
                    element,
                    format!("sparse data of {n} elements exceeds its bufferViews"),
                ));
            }
            for k in 0..n {
                let at = indices.offset() + k * index_size;
                let b = &index_bytes[at..at + index_size];
                let target = match index_size {
                    1 => usize::from(b[0]),
                    2 => usize::from(u16::from_le_bytes([b[0], b[1]])),
                    _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
                };
                if target >= count {
                    return Err(self.err(
                        element,
                        format!("sparse index {target} out of range for {count} elements"),
                    ));
                }
                for c in 0..comps {
                    let at = sparse.values().offset() + k * elem_size + c * comp_size;
                    out[target * comps + c] = convert(&value_bytes[at..at + comp_size]);
                }
            }
        }
        Ok(out)
    }
}
