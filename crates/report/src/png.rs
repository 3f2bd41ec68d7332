//! SVG figures rasterised to PNG with resvg (pure Rust), for journals that
//! ask for bitmaps. Text needs a sans-serif system font: Liberation Sans
//! (metric-compatible with Arial) when installed, else DejaVu Sans, else the
//! first sans font found; with none, the export says so instead of writing
//! figures without their labels.

use std::sync::{Arc, OnceLock};

use resvg::{tiny_skia, usvg};

/// Pixels per SVG pixel: a 560 px wide figure becomes 1680 px, 480 dpi at
/// one column (89 mm).
pub const SCALE: f32 = 3.0;

/// The system fonts, loaded once; Err when there is no sans-serif font.
fn fonts() -> Result<Arc<usvg::fontdb::Database>, String> {
    static FONTS: OnceLock<Result<Arc<usvg::fontdb::Database>, String>> = OnceLock::new();
    FONTS
        .get_or_init(|| {
            let mut db = usvg::fontdb::Database::new();
            db.load_system_fonts();
            let families: Vec<String> = db
                .faces()
                .flat_map(|f| f.families.iter().map(|(name, _)| name.clone()))
                .collect();
            let sans = ["Liberation Sans", "DejaVu Sans", "Arial", "Helvetica"]
                .into_iter()
                .find(|want| families.iter().any(|f| f == want))
                .map(str::to_string)
                .or_else(|| families.iter().find(|f| f.contains("Sans")).cloned());
            match sans {
                Some(family) => {
                    db.set_sans_serif_family(family);
                    Ok(Arc::new(db))
                }
                None => Err("PNG figures need a sans-serif system font for their labels and none was found (Debian: apt-get install fonts-dejavu-core); the SVG figures were written".into()),
            }
        })
        .clone()
}

/// The SVG as PNG bytes at [`SCALE`] x its size, on white.
pub fn svg_to_png(svg: &str) -> Result<Vec<u8>, String> {
    let options = usvg::Options {
        fontdb: fonts()?,
        ..usvg::Options::default()
    };
    let tree = usvg::Tree::from_str(svg, &options).map_err(|e| format!("figure SVG: {e}"))?;
    let size = tree.size();
    let (w, h) = (
        (size.width() * SCALE).ceil() as u32,
        (size.height() * SCALE).ceil() as u32,
    );
    let mut pixmap = tiny_skia::Pixmap::new(w.max(1), h.max(1))
        .ok_or_else(|| format!("figure of {w} x {h} px is too large to rasterise"))?;
    pixmap.fill(tiny_skia::Color::WHITE);
    resvg::render(
        &tree,
        tiny_skia::Transform::from_scale(SCALE, SCALE),
        &mut pixmap.as_mut(),
    );
    pixmap
        .encode_png()
        .map_err(|e| format!("PNG encoding: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_chart_becomes_a_png_of_three_times_its_size_with_its_text_drawn() {
        let svg = r##"<svg xmlns="http://www.w3.org/2000/svg" width="100" height="40" viewBox="0 0 100 40" font-family="sans-serif" font-size="15"><rect width="100" height="40" fill="#fff"/><text x="5" y="25">N/m</text></svg>"##;
        let without_text = svg.replace("N/m", "");
        let (png, blank) = match (svg_to_png(svg), svg_to_png(&without_text)) {
            (Ok(a), Ok(b)) => (a, b),
            (Err(e), _) | (_, Err(e)) => {
                // no font on this machine: the error says so, in one line
                assert!(e.contains("font") && !e.contains('\n'), "{e}");
                return;
            }
        };
        assert!(png.starts_with(b"\x89PNG"));
        // IHDR: width and height, big-endian, at bytes 16..24
        let dim = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
        assert_eq!((dim(&png[16..20]), dim(&png[20..24])), (300, 120));
        // the label changes the pixels
        assert_ne!(png, blank);
    }
}
