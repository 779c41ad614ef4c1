//! Bodies for the jobs, cached in `OUT/bodies/`.
//!
//! A measurements body is fitted once (`drapekit fit --measurements M --to-units m --to-up y`)
//! into `OUT/bodies/<name>-<h>.obj`, `h` a hash of the measurement file's bytes, so an edited
//! file is fitted again and an unchanged one never. A scene job takes the body as its object's
//! mesh (its up axis in the object's `up`, the size in its `scale`). A pattern job needs the
//! body y up and sized: a mesh body that is y up at scale 1 is used as it is; any other is
//! written once, turned and scaled about its origin, into `OUT/bodies/<name>-<size>-<h>.obj`.

use super::plan::{short_hash, Body, BodySource};
use super::BatchError;
use crate::io::{self, ReadOptions, WriteOptions};
use crate::mesh::transform::{change_up, Up};
use std::path::{Path, PathBuf};
use std::process::Command;

/// A body file ready for a job, and its up axis.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyMesh {
    /// The mesh file.
    pub file: PathBuf,
    /// Its up axis.
    pub up: Up,
}

fn read_bytes(path: &Path) -> Result<Vec<u8>, BatchError> {
    std::fs::read(path).map_err(|source| BatchError::Read {
        path: path.to_path_buf(),
        source,
    })
}

fn bodies_dir(out: &Path) -> Result<PathBuf, BatchError> {
    let d = out.join("bodies");
    std::fs::create_dir_all(&d).map_err(|source| BatchError::Write {
        path: d.clone(),
        source,
    })?;
    Ok(d)
}

/// The body as a mesh file: the mesh itself, or the fitted form (fitted by `exe` when not
/// cached yet).
pub fn mesh(body: &Body, out: &Path, exe: &Path) -> Result<BodyMesh, BatchError> {
    match &body.source {
        BodySource::Mesh { file, up } => Ok(BodyMesh {
            file: file.clone(),
            up: *up,
        }),
        BodySource::Measurements { file } => {
            let h = short_hash(&read_bytes(file)?);
            let form = bodies_dir(out)?.join(format!("{}-{h}.obj", body.name));
            if !form.is_file() {
                fit(exe, file, &form)?;
            }
            Ok(BodyMesh {
                file: form,
                up: Up::Y,
            })
        }
    }
}

/// Runs `exe fit` on a measurement file; the form is written atomically by `fit` itself.
fn fit(exe: &Path, measurements: &Path, form: &Path) -> Result<(), BatchError> {
    let what = format!("fitting {}", measurements.display());
    let o = Command::new(exe)
        .args(["--jobs", "1", "fit", "--measurements"])
        .arg(measurements)
        .arg("-o")
        .arg(form)
        .args(["--to-units", "m", "--to-up", "y"])
        .output()
        .map_err(|e| BatchError::Child {
            what: what.clone(),
            message: format!("cannot start {}: {e}", exe.display()),
        })?;
    if o.status.success() {
        Ok(())
    } else {
        Err(BatchError::Child {
            what,
            message: String::from_utf8_lossy(&o.stderr).trim().to_string(),
        })
    }
}

/// The body y up and scaled by `scale`, for a pattern job (`size` names the scale in the cached
/// file's name).
pub fn for_pattern(
    body: &Body,
    size: Option<(&str, f64)>,
    out: &Path,
    exe: &Path,
) -> Result<PathBuf, BatchError> {
    let m = mesh(body, out, exe)?;
    let (size_name, scale) = size.unwrap_or(("1", 1.0));
    if m.up == Up::Y && scale == 1.0 {
        return Ok(m.file);
    }
    let mut key = read_bytes(&m.file)?;
    key.extend(format!("|{:?}|{scale:e}", m.up).bytes());
    let h = short_hash(&key);
    let file = bodies_dir(out)?.join(format!("{}-{size_name}-{h}.obj", body.name));
    if !file.is_file() {
        let mut mesh = io::read_mesh(&m.file, &ReadOptions::default())?.mesh;
        change_up(&mut mesh, m.up, Up::Y);
        for p in &mut mesh.positions {
            *p *= scale;
        }
        io::write_mesh(&file, &mesh, &WriteOptions::default(), &[&m.file])?;
    }
    Ok(file)
}
