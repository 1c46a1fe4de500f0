//! A small PNG scatter chart (cost against error), drawn directly with `image` and a built-in
//! 5×7 bitmap font, so that no font files or plotting dependencies are needed.

use crate::error::{Error, Result};
use crate::outputs::OutputFile;
use image::{ImageEncoder, Rgb, RgbImage};

/// One point of the chart.
pub struct Point {
    /// Label drawn next to the point.
    pub label: String,
    /// Cost (x axis, linear), e.g. ns per test.
    pub x: f64,
    /// Error (y axis, log scale; 0 is drawn on the bottom line), e.g. leaks per million.
    pub y: f64,
}

const W: u32 = 960;
const H: u32 = 600;
const LEFT: i32 = 110;
const RIGHT: i32 = 40;
const TOP: i32 = 50;
const BOTTOM: i32 = 70;
const SCALE: i32 = 2;
/// Decades shown on the y axis above the zero line: 10⁰ … 10⁶ per million.
const DECADES: i32 = 6;

const PALETTE: [[u8; 3]; 8] = [
    [31, 119, 180],
    [214, 39, 40],
    [44, 160, 44],
    [255, 127, 14],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [23, 190, 207],
];

/// Draws the chart and writes it to a reserved output as PNG (atomically).
pub fn write_chart(
    out: OutputFile,
    title: &str,
    x_label: &str,
    y_label: &str,
    points: &[Point],
) -> Result<()> {
    let mut img = RgbImage::from_pixel(W, H, Rgb([255, 255, 255]));
    let (pw, ph) = (W as i32 - LEFT - RIGHT, H as i32 - TOP - BOTTOM);
    let x_max = points.iter().map(|p| p.x).fold(0.0, f64::max).max(1.0e-9) * 1.15;
    let grey = Rgb([220, 220, 220]);
    let black = Rgb([0, 0, 0]);
    // y: the zero line at the bottom, then one band per decade.
    let band = ph / (DECADES + 1);
    let y_of = |y: f64| -> i32 {
        if y <= 0.0 {
            TOP + ph
        } else {
            let d = y.log10().clamp(0.0, DECADES as f64);
            TOP + ph - band - (d * band as f64) as i32
        }
    };
    for k in 0..=DECADES {
        let yy = TOP + ph - band - k * band;
        hline(&mut img, LEFT, LEFT + pw, yy, grey);
        text(&mut img, LEFT - 70, yy - 7, &format!("1e{k}"), black);
    }
    text(&mut img, LEFT - 30, TOP + ph - 7, "0", black);
    for k in 0..=5 {
        let xv = x_max * k as f64 / 5.0;
        let xx = LEFT + (pw as f64 * k as f64 / 5.0) as i32;
        vline(&mut img, xx, TOP, TOP + ph, grey);
        text(&mut img, xx - 12, TOP + ph + 10, &format!("{xv:.1}"), black);
    }
    hline(&mut img, LEFT, LEFT + pw, TOP + ph, black);
    vline(&mut img, LEFT, TOP, TOP + ph, black);
    text(&mut img, 8, 4, title, black);
    text(
        &mut img,
        LEFT + pw / 2 - 6 * x_label.len() as i32,
        H as i32 - 30,
        x_label,
        black,
    );
    text(&mut img, 8, 24, y_label, black);
    // Legend in the plot's upper-left corner; points drawn largest-first so none hides.
    let legend_x = LEFT + 16;
    for (i, p) in points.iter().enumerate() {
        let c = Rgb(PALETTE[i % PALETTE.len()]);
        let ly = TOP + 14 + i as i32 * 20;
        disc(&mut img, legend_x, ly + 6, 5, c);
        text(&mut img, legend_x + 12, ly, &p.label, c);
    }
    for (i, p) in points.iter().enumerate().rev() {
        let c = Rgb(PALETTE[i % PALETTE.len()]);
        let px = LEFT + (pw as f64 * p.x / x_max) as i32;
        disc(&mut img, px, y_of(p.y), 7 - (i as i32 % 3), c);
    }
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(img.as_raw(), W, H, image::ExtendedColorType::Rgb8)
        .map_err(|e| Error::encode("the chart", e))?;
    out.write(|w| w.write_all(&png))
}

fn put(img: &mut RgbImage, x: i32, y: i32, c: Rgb<u8>) {
    if x >= 0 && y >= 0 && (x as u32) < img.width() && (y as u32) < img.height() {
        img.put_pixel(x as u32, y as u32, c);
    }
}

fn hline(img: &mut RgbImage, x0: i32, x1: i32, y: i32, c: Rgb<u8>) {
    for x in x0..=x1 {
        put(img, x, y, c);
    }
}

fn vline(img: &mut RgbImage, x: i32, y0: i32, y1: i32, c: Rgb<u8>) {
    for y in y0..=y1 {
        put(img, x, y, c);
    }
}

fn disc(img: &mut RgbImage, cx: i32, cy: i32, r: i32, c: Rgb<u8>) {
    for y in -r..=r {
        for x in -r..=r {
            if x * x + y * y <= r * r {
                put(img, cx + x, cy + y, c);
            }
        }
    }
}

/// Draws `s` with the 5×7 font scaled by [`SCALE`]; unknown characters are left blank.
fn text(img: &mut RgbImage, x: i32, y: i32, s: &str, c: Rgb<u8>) {
    for (i, ch) in s.chars().enumerate() {
        let rows = glyph(ch.to_ascii_lowercase());
        let gx = x + i as i32 * 6 * SCALE;
        for (ry, row) in rows.iter().enumerate() {
            for rx in 0..5 {
                if row & (0x10 >> rx) != 0 {
                    for sy in 0..SCALE {
                        for sx in 0..SCALE {
                            put(img, gx + rx * SCALE + sx, y + ry as i32 * SCALE + sy, c);
                        }
                    }
                }
            }
        }
    }
}

fn glyph(c: char) -> [u8; 7] {
    match c {
        '0' => [14, 17, 19, 21, 25, 17, 14],
        '1' => [4, 12, 4, 4, 4, 4, 14],
        '2' => [14, 17, 1, 2, 4, 8, 31],
        '3' => [31, 2, 4, 2, 1, 17, 14],
        '4' => [2, 6, 10, 18, 31, 2, 2],
        '5' => [31, 16, 30, 1, 1, 17, 14],
        '6' => [6, 8, 16, 30, 17, 17, 14],
        '7' => [31, 1, 2, 4, 8, 8, 8],
        '8' => [14, 17, 17, 14, 17, 17, 14],
        '9' => [14, 17, 17, 15, 1, 2, 12],
        'a' => [0, 0, 14, 1, 15, 17, 15],
        'b' => [16, 16, 22, 25, 17, 17, 30],
        'c' => [0, 0, 14, 16, 16, 17, 14],
        'd' => [1, 1, 13, 19, 17, 17, 15],
        'e' => [0, 0, 14, 17, 31, 16, 14],
        'f' => [6, 9, 8, 28, 8, 8, 8],
        'g' => [0, 15, 17, 17, 15, 1, 14],
        'h' => [16, 16, 22, 25, 17, 17, 17],
        'i' => [4, 0, 12, 4, 4, 4, 14],
        'j' => [2, 0, 6, 2, 2, 18, 12],
        'k' => [16, 16, 18, 20, 24, 20, 18],
        'l' => [12, 4, 4, 4, 4, 4, 14],
        'm' => [0, 0, 26, 21, 21, 17, 17],
        'n' => [0, 0, 22, 25, 17, 17, 17],
        'o' => [0, 0, 14, 17, 17, 17, 14],
        'p' => [0, 0, 30, 17, 30, 16, 16],
        'q' => [0, 0, 13, 19, 15, 1, 1],
        'r' => [0, 0, 22, 25, 16, 16, 16],
        's' => [0, 0, 14, 16, 14, 1, 30],
        't' => [8, 8, 28, 8, 8, 9, 6],
        'u' => [0, 0, 17, 17, 17, 19, 13],
        'v' => [0, 0, 17, 17, 17, 10, 4],
        'w' => [0, 0, 17, 17, 21, 21, 10],
        'x' => [0, 0, 17, 10, 4, 10, 17],
        'y' => [0, 0, 17, 17, 15, 1, 14],
        'z' => [0, 0, 31, 2, 4, 8, 31],
        '-' => [0, 0, 0, 31, 0, 0, 0],
        '.' => [0, 0, 0, 0, 0, 12, 12],
        '+' => [0, 4, 4, 31, 4, 4, 0],
        '/' => [0, 1, 2, 4, 8, 16, 0],
        '(' => [2, 4, 8, 8, 8, 4, 2],
        ')' => [8, 4, 2, 2, 2, 4, 8],
        ':' => [0, 12, 12, 0, 12, 12, 0],
        '=' => [0, 0, 31, 0, 31, 0, 0],
        _ => [0; 7],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chart_is_a_png_of_the_stated_size_with_coloured_points() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.png");
        let pts = vec![
            Point {
                label: "watertight".into(),
                x: 8.0,
                y: 0.0,
            },
            Point {
                label: "moller-trumbore".into(),
                x: 6.0,
                y: 12_000.0,
            },
        ];
        write_chart(
            OutputFile::reserve(&path, false).unwrap(),
            "cost vs error",
            "ns per test",
            "leaks per million",
            &pts,
        )
        .unwrap();
        let img = image::open(&path).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (W, H));
        let blue = img.pixels().filter(|p| p.0 == PALETTE[0]).count();
        let red = img.pixels().filter(|p| p.0 == PALETTE[1]).count();
        assert!(blue > 100 && red > 100, "{blue} {red}");
    }
}
