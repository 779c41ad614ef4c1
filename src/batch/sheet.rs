//! The contact sheet: every done job's main mesh drawn small (`render`, iso view), in position
//! order, four to a row, each cell labelled with its position (the row of `results.csv`).

use super::collect::Row;
use super::error::BatchError;
use super::status::State;
use crate::mesh::transform::Up;
use crate::render::{self, Item, Layout, RenderOptions};
use std::path::{Path, PathBuf};

/// The cloth's colour (terracotta, as `render` draws it).
const CLOTH: [u8; 3] = [0xe0, 0x7a, 0x5f];

/// Cells per row of the sheet.
pub const COLUMNS: u32 = 4;
/// A cell's size, px.
pub const CELL: (u32, u32) = (240, 180);

/// Draws `OUT/contact_sheet.png` from the done rows (atomically); `None` when no job is done.
/// A mesh that cannot be read or drawn leaves its cell empty, with its label.
pub fn write(out: &Path, rows: &[Row]) -> Result<Option<PathBuf>, BatchError> {
    let done: Vec<&Row> = (rows.iter())
        .filter(|r| r.state == State::Done && r.mesh.is_some())
        .collect();
    if done.is_empty() {
        return Ok(None);
    }
    let n = done.len() as u32;
    let (w, h) = CELL;
    let mut sheet =
        render::image::Image::new(w * COLUMNS.min(n), h * n.div_ceil(COLUMNS), [255; 3]);
    for (k, r) in done.iter().enumerate() {
        let (cx, cy) = ((k as u32 % COLUMNS) * w, (k as u32 / COLUMNS) * h);
        if let Some(cell) = thumbnail(&out.join(r.mesh.as_deref().unwrap_or("")), &r.kind) {
            for y in 0..h {
                for x in 0..w {
                    sheet.put(i64::from(cx + x), i64::from(cy + y), cell.get(x, y));
                }
            }
        }
        let label = r.position.to_string();
        render::font::draw_text(
            &mut sheet,
            i64::from(cx) + 6,
            i64::from(cy) + 6,
            &label,
            2,
            [0; 3],
        );
    }
    let path = out.join("contact_sheet.png");
    crate::io::write_atomic(&path, &[], |f| render::image::write_png(f, &sheet))?;
    Ok(Some(path))
}

/// One mesh drawn in a cell: garments are y up, scenes z up.
fn thumbnail(mesh: &Path, kind: &str) -> Option<render::image::Image> {
    let m = crate::io::read_mesh(mesh, &Default::default()).ok()?.mesh;
    let opts = RenderOptions {
        width: CELL.0,
        height: CELL.1,
        layout: Layout::default(),
        up: if kind == "garment" { Up::Y } else { Up::Z },
        ..RenderOptions::default()
    };
    let item = Item::cloth(&m, CLOTH, None, 0.0);
    render::render_fitted(&[item], &opts).ok()
}
