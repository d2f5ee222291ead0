//! Export of the world triangles at the current poses, so a frame can be checked in another tool
//! (MeshLab, Blender, Open3D, trimesh).
//!
//! PLY is binary little-endian with per-face `class` and `instance` properties; OBJ is plain text with
//! one `g instance_<id>` group per instance.

use crate::error::{MmusvError, Result};
use crate::scene::WorldMesh;
use std::io::{BufWriter, Write};
use std::path::Path;

/// File formats [`write_world_mesh`] can produce.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// Binary little-endian PLY with per-face class and instance.
    Ply,
    /// Wavefront OBJ, one group per instance.
    Obj,
}

impl MeshFormat {
    /// Picks the format from a file name's extension (`.ply` or `.obj`, any case).
    pub fn from_path(path: &Path) -> Result<Self> {
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("ply") => Ok(Self::Ply),
            Some("obj") => Ok(Self::Obj),
            other => Err(MmusvError::input(
                "path",
                match other {
                    Some(ext) => format!("extension .{ext} is not supported; use .ply or .obj"),
                    None => "a file name without extension is not supported; use .ply or .obj".to_string(),
                },
            )),
        }
    }
}

/// Writes `mesh` to `path` in `format`. The file is written to a temporary name and renamed into place, so a
/// failure never leaves a half-written file under `path`.
pub fn write_world_mesh(mesh: &WorldMesh, path: &Path, format: MeshFormat) -> Result<()> {
    let io = |e: std::io::Error| MmusvError::Io { path: path.display().to_string(), reason: e.to_string() };
    let tmp = path.with_extension(format!("{}.partial", path.extension().and_then(|e| e.to_str()).unwrap_or("mesh")));
    let file = std::fs::File::create(&tmp).map_err(io)?;
    let mut w = BufWriter::new(file);
    let result = match format {
        MeshFormat::Ply => write_ply(mesh, &mut w),
        MeshFormat::Obj => write_obj(mesh, &mut w),
    }
    .and_then(|_| w.flush());
    drop(w);
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(io(e));
    }
    std::fs::rename(&tmp, path).map_err(io)
}

fn write_ply(m: &WorldMesh, w: &mut impl Write) -> std::io::Result<()> {
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\ncomment mmusv world triangles, world frame, metres\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar int vertex_indices\nproperty ushort class\nproperty uint instance\n\
         end_header\n",
        m.vertices.len(),
        m.faces.len()
    )?;
    for v in &m.vertices {
        for c in v {
            w.write_all(&c.to_le_bytes())?;
        }
    }
    for ((f, c), i) in m.faces.iter().zip(&m.classes).zip(&m.instances) {
        w.write_all(&[3u8])?;
        for k in f {
            w.write_all(&(*k as i32).to_le_bytes())?;
        }
        w.write_all(&c.to_le_bytes())?;
        w.write_all(&i.to_le_bytes())?;
    }
    Ok(())
}

fn write_obj(m: &WorldMesh, w: &mut impl Write) -> std::io::Result<()> {
    writeln!(w, "# mmusv world triangles, world frame, metres")?;
    for v in &m.vertices {
        writeln!(w, "v {} {} {}", v[0], v[1], v[2])?;
    }
    let mut current = u32::MAX;
    for (f, i) in m.faces.iter().zip(&m.instances) {
        if *i != current {
            writeln!(w, "g instance_{i}")?;
            current = *i;
        }
        writeln!(w, "f {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ply_and_obj_roundtrip_sizes() {
        let m = WorldMesh {
            vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            faces: vec![[0, 1, 2]],
            classes: vec![4],
            instances: vec![2],
            triangles: vec![0],
        };
        let dir = std::env::temp_dir().join(format!("mmusv-export-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap_or(());
        let ply = dir.join("w.ply");
        write_world_mesh(&m, &ply, MeshFormat::from_path(&ply).unwrap_or(MeshFormat::Obj)).unwrap_or(());
        let bytes = std::fs::read(&ply).unwrap_or_default();
        let header_end = bytes.windows(11).position(|w| w == b"end_header\n").map_or(0, |p| p + 11);
        assert_eq!(bytes.len() - header_end, 3 * 12 + (1 + 12 + 2 + 4));
        let obj = dir.join("w.obj");
        write_world_mesh(&m, &obj, MeshFormat::Obj).unwrap_or(());
        let text = std::fs::read_to_string(&obj).unwrap_or_default();
        assert!(text.contains("g instance_2") && text.contains("f 1 2 3"));
        let said = |p: &str| MeshFormat::from_path(Path::new(p)).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(said("x.stl").contains("extension .stl is not supported"), "{}", said("x.stl"));
        assert!(said("x").contains("without extension"), "{}", said("x"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
