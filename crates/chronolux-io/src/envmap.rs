//! Reading environment maps: equirectangular images of linear radiance from OpenEXR
//! (`.exr`, through [`crate::image::read_exr`]) or Radiance RGBE (`.hdr`, `.pic`: the
//! reader here, flat and run-length-encoded scanlines), into the texels
//! [`chronolux_core::light::EnvMap::new`] takes. Every malformed file is an error that
//! names the file and what is wrong, never a panic.

use crate::image::{Image, ImageError, read_exr};
use chronolux_core::color::Rgb;
use std::path::Path;

/// Largest map accepted (texels): 2^28, e.g. 32768 × 8192 (a 32k HDRI is 32768 × 16384 =
/// 2^29 and would need 6 GB as f32 RGB; refuse rather than exhaust memory on a header).
pub const MAX_TEXELS: usize = 1 << 28;

/// Reads an equirectangular environment map by its extension (`.exr`, `.hdr`, `.pic`).
pub fn read_environment(path: impl AsRef<Path>) -> Result<Image, ImageError> {
    let path = path.as_ref();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let image = match ext.as_deref() {
        Some("exr") => read_exr(path)?,
        Some("hdr") | Some("pic") | Some("rgbe") => {
            let bytes = std::fs::read(path).map_err(|source| ImageError::Read {
                path: path.to_owned(),
                source,
            })?;
            decode_hdr(&bytes).map_err(|reason| ImageError::Invalid {
                path: path.to_owned(),
                reason: format!("not a readable Radiance HDR file: {reason}"),
            })?
        }
        _ => {
            return Err(ImageError::Invalid {
                path: path.to_owned(),
                reason: "an environment map must be an OpenEXR (.exr) or Radiance HDR (.hdr) \
                         file of linear radiance"
                    .into(),
            });
        }
    };
    if image.width < 2 || image.height < 1 {
        return Err(ImageError::Invalid {
            path: path.to_owned(),
            reason: format!(
                "environment map of {}x{} texels is too small (at least 2x1)",
                image.width, image.height
            ),
        });
    }
    Ok(image)
}

/// Decodes a Radiance RGBE file (`#?RADIANCE` / `#?RGBE` header, `FORMAT=32-bit_rle_rgbe`,
/// resolution `-Y H +X W` or `+Y H +X W`). Values as Blender reads them: (m + 0.5)·2^(e−136).
pub fn decode_hdr(bytes: &[u8]) -> Result<Image, String> {
    let mut pos = 0usize;
    let line = |pos: &mut usize| -> Result<String, String> {
        let rest = &bytes[*pos..];
        let end = rest
            .iter()
            .position(|&b| b == b'\n')
            .ok_or("the header ends without a resolution line")?;
        if end > 4096 {
            return Err("header line longer than 4096 bytes".into());
        }
        *pos += end + 1;
        Ok(String::from_utf8_lossy(&rest[..end]).trim_end().to_string())
    };
    let first = line(&mut pos)?;
    if !first.starts_with("#?") {
        return Err("missing the #?RADIANCE signature".into());
    }
    loop {
        let l = line(&mut pos)?;
        if l.is_empty() {
            break;
        }
        if let Some(f) = l.strip_prefix("FORMAT=")
            && f.trim() != "32-bit_rle_rgbe"
        {
            return Err(format!(
                "pixel format {} (only 32-bit_rle_rgbe, RGB, is read)",
                f.trim()
            ));
        }
    }
    let res = line(&mut pos)?;
    let parts: Vec<&str> = res.split_whitespace().collect();
    let (flip, height, width) = match parts.as_slice() {
        [y, h, "+X", w] if *y == "-Y" || *y == "+Y" => {
            let h: usize = h
                .parse()
                .map_err(|_| format!("bad height in resolution line '{res}'"))?;
            let w: usize = w
                .parse()
                .map_err(|_| format!("bad width in resolution line '{res}'"))?;
            (*y == "+Y", h, w)
        }
        _ => {
            return Err(format!(
                "resolution line '{res}': only '-Y H +X W' and '+Y H +X W' orientations are read"
            ));
        }
    };
    if width == 0 || height == 0 {
        return Err(format!("empty image ({width}x{height})"));
    }
    if width.checked_mul(height).is_none_or(|n| n > MAX_TEXELS) {
        return Err(format!(
            "{width}x{height} texels is more than the {MAX_TEXELS} accepted"
        ));
    }
    let data = &bytes[pos..];
    let mut rgbe = vec![[0u8; 4]; width * height];
    let mut at = 0usize;
    let truncated = || format!("pixel data ends early ({width}x{height} expected)");
    for y in 0..height {
        let row = &mut rgbe[y * width..(y + 1) * width];
        let new_rle = (8..32768).contains(&width)
            && data.len() >= at + 4
            && data[at] == 2
            && data[at + 1] == 2
            && data[at + 2] & 0x80 == 0;
        if new_rle {
            let w = ((data[at + 2] as usize) << 8) | data[at + 3] as usize;
            if w != width {
                return Err(format!("scanline {y} is {w} wide in a {width}-wide image"));
            }
            at += 4;
            for c in 0..4 {
                let mut x = 0usize;
                while x < width {
                    let &n = data.get(at).ok_or_else(truncated)?;
                    at += 1;
                    if n > 128 {
                        let run = (n - 128) as usize;
                        let &v = data.get(at).ok_or_else(truncated)?;
                        at += 1;
                        if x + run > width {
                            return Err(format!("run-length overflows scanline {y}"));
                        }
                        for p in &mut row[x..x + run] {
                            p[c] = v;
                        }
                        x += run;
                    } else {
                        let n = n as usize;
                        if n == 0 || x + n > width {
                            return Err(format!("bad literal run in scanline {y}"));
                        }
                        let src = data.get(at..at + n).ok_or_else(truncated)?;
                        for (p, &v) in row[x..x + n].iter_mut().zip(src) {
                            p[c] = v;
                        }
                        at += n;
                        x += n;
                    }
                }
            }
        } else {
            // Flat pixels, with the old run-length scheme: (1, 1, 1, n) repeats the
            // previous pixel n << shift times.
            let mut x = 0usize;
            let mut shift = 0u32;
            while x < width {
                let p = data.get(at..at + 4).ok_or_else(truncated)?;
                at += 4;
                let p = [p[0], p[1], p[2], p[3]];
                if p[0] == 1 && p[1] == 1 && p[2] == 1 {
                    if x == 0 || shift > 24 {
                        return Err(format!("bad old-style run in scanline {y}"));
                    }
                    let run = (p[3] as usize) << shift;
                    if x + run > width {
                        return Err(format!("run-length overflows scanline {y}"));
                    }
                    let prev = row[x - 1];
                    for q in &mut row[x..x + run] {
                        *q = prev;
                    }
                    x += run;
                    shift += 8;
                } else {
                    row[x] = p;
                    x += 1;
                    shift = 0;
                }
            }
        }
    }
    let mut pixels = Vec::with_capacity(width * height);
    for y in 0..height {
        let src = if flip { height - 1 - y } else { y };
        for p in &rgbe[src * width..(src + 1) * width] {
            pixels.push(rgbe_to_rgb(*p));
        }
    }
    Ok(Image::from_pixels(width as u32, height as u32, pixels))
}

fn rgbe_to_rgb(p: [u8; 4]) -> Rgb {
    if p[3] == 0 {
        return Rgb::ZERO;
    }
    let f = 2f32.powi(p[3] as i32 - 136);
    Rgb::new(
        (p[0] as f32 + 0.5) * f,
        (p[1] as f32 + 0.5) * f,
        (p[2] as f32 + 0.5) * f,
    )
}

/// Encodes linear RGB as RGBE (the inverse of the reader's decoding, to within the
/// format's 8-bit mantissa): used by tests and to write maps.
pub fn rgb_to_rgbe(c: Rgb) -> [u8; 4] {
    let v = c.x.max(c.y).max(c.z);
    if !(v > 1e-32) || !v.is_finite() {
        return [0; 4];
    }
    // v = m · 2^e with m in [0.5, 1).
    let e = v.log2().floor() as i32 + 1;
    let scale = 256.0 / 2f32.powi(e);
    let q = |x: f32| ((x.max(0.0) * scale - 0.5).round().clamp(0.0, 255.0)) as u8;
    [q(c.x), q(c.y), q(c.z), (e + 128).clamp(0, 255) as u8]
}

/// A Radiance HDR file of `image` (flat scanlines, no run-length encoding).
pub fn encode_hdr(image: &Image) -> Vec<u8> {
    let mut out = format!(
        "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {} +X {}\n",
        image.height, image.width
    )
    .into_bytes();
    for p in &image.pixels {
        out.extend_from_slice(&rgb_to_rgbe(*p));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A new-style RLE scanline encoder (runs of ≥ 3 equal bytes as runs), for the reader's
    /// test: the reader must give back what `encode_hdr`'s flat form gives.
    fn encode_rle(image: &Image) -> Vec<u8> {
        let mut out = format!(
            "#?RGBE\nEXPOSURE=1.0\nFORMAT=32-bit_rle_rgbe\n\n-Y {} +X {}\n",
            image.height, image.width
        )
        .into_bytes();
        let w = image.width as usize;
        for row in image.pixels.chunks(w) {
            out.extend_from_slice(&[2, 2, (w >> 8) as u8, (w & 255) as u8]);
            let px: Vec<[u8; 4]> = row.iter().map(|&c| rgb_to_rgbe(c)).collect();
            for c in 0..4 {
                let ch: Vec<u8> = px.iter().map(|p| p[c]).collect();
                let mut x = 0;
                while x < w {
                    let mut run = 1;
                    while x + run < w && run < 127 && ch[x + run] == ch[x] {
                        run += 1;
                    }
                    if run >= 3 {
                        out.extend_from_slice(&[128 + run as u8, ch[x]]);
                        x += run;
                    } else {
                        let mut n = 1;
                        while x + n < w
                            && n < 128
                            && !(x + n + 2 < w
                                && ch[x + n] == ch[x + n + 1]
                                && ch[x + n] == ch[x + n + 2])
                        {
                            n += 1;
                        }
                        out.push(n as u8);
                        out.extend_from_slice(&ch[x..x + n]);
                        x += n;
                    }
                }
            }
        }
        out
    }

    fn test_image() -> Image {
        let (w, h) = (40u32, 6u32);
        let pixels = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if x < 12 {
                    Rgb::new(0.25, 0.5, 1.0) // a run
                } else {
                    Rgb::new(
                        x as f32 * 0.37,
                        y as f32 * 3.1 + 0.01,
                        1000.0 / (1 + x) as f32,
                    )
                }
            })
            .collect();
        Image::from_pixels(w, h, pixels)
    }

    #[test]
    fn flat_and_rle_files_decode_to_the_encoded_values() {
        let img = test_image();
        let flat = decode_hdr(&encode_hdr(&img)).unwrap();
        let rle = decode_hdr(&encode_rle(&img)).unwrap();
        assert_eq!(flat, rle);
        assert_eq!((flat.width, flat.height), (img.width, img.height));
        for (a, b) in img.pixels.iter().zip(&flat.pixels) {
            // RGBE keeps 8 bits of mantissa for the largest channel: relative error of
            // that channel ≤ 2^-8; smaller channels ≤ 2^-8 of the largest.
            let m = a.max_element();
            assert!(
                (*a - *b).abs().max_element() <= m / 256.0 + 1e-30,
                "{a} vs {b}"
            );
        }
    }

    #[test]
    fn malformed_files_are_errors_not_panics() {
        let good = encode_rle(&test_image());
        assert!(decode_hdr(b"").is_err());
        assert!(decode_hdr(b"P6\n1 1\n").is_err());
        assert!(decode_hdr(b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\n\0\0\0\0").is_err());
        assert!(decode_hdr(b"#?RADIANCE\n\n+X 1 -Y 1\n\0\0\0\0").is_err());
        assert!(decode_hdr(b"#?RADIANCE\n\n-Y 99999999 +X 99999999\n").is_err());
        // Every truncation of a valid file fails cleanly (or, past the data, succeeds).
        for n in 0..good.len() {
            assert!(decode_hdr(&good[..n]).is_err(), "truncated at {n} accepted");
        }
        // Corrupted bytes: never a panic.
        let mut rng = 12345u64;
        for _ in 0..2000 {
            let mut b = good.clone();
            rng = rng
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let i = (rng >> 33) as usize % b.len();
            b[i] = (rng >> 20) as u8;
            let _ = decode_hdr(&b);
        }
    }

    #[test]
    fn plus_y_files_are_flipped() {
        let img = test_image();
        let mut bytes = encode_hdr(&img);
        let at = bytes.windows(4).position(|w| w == b"-Y 6").unwrap();
        bytes[at] = b'+';
        let f = decode_hdr(&bytes).unwrap();
        let d = decode_hdr(&encode_hdr(&img)).unwrap();
        for y in 0..6 {
            assert_eq!(f.get(3, y), d.get(3, 5 - y));
        }
    }
}
