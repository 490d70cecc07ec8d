//! Tone mapping and PNG output shared by the example programs.

use std::path::{Path, PathBuf};

use arealight::glam::DVec3;

/// Where the examples write their outputs: `target/arealight-out/` in the repository (this
/// package is its `demo/` folder).
pub fn default_out() -> PathBuf {
    crate::repo_path("target/arealight-out")
}

/// The output folder, [`default_out`], created if needed.
pub fn out_dir() -> Result<PathBuf, String> {
    let d = default_out();
    std::fs::create_dir_all(&d).map_err(|e| format!("{}: {e}", d.display()))?;
    Ok(d)
}

/// Linear radiance to an 8-bit sRGB value after the tone map `1 - exp(-exposure x)`.
pub fn srgb(x: f64, exposure: f64) -> u8 {
    let t = 1.0 - (-exposure * x.max(0.0)).exp();
    let s = if t <= 0.003_130_8 {
        12.92 * t
    } else {
        1.055 * t.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5).clamp(0.0, 255.0) as u8
}

/// An RGB image of linear radiance as tone-mapped 8-bit sRGB bytes.
pub fn to_bytes(img: &[DVec3], exposure: f64) -> Vec<u8> {
    img.iter()
        .flat_map(|p| {
            [
                srgb(p.x, exposure),
                srgb(p.y, exposure),
                srgb(p.z, exposure),
            ]
        })
        .collect()
}

/// Writes 8-bit RGB pixels as a PNG.
pub fn write_png(path: &Path, w: usize, h: usize, rgb: &[u8]) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w as u32, h as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut wr = enc.write_header().map_err(|e| e.to_string())?;
    wr.write_image_data(rgb).map_err(|e| e.to_string())
}
