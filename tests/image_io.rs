//! Luminance images: files decode with the `image` crate and show what they should.

use lumest::io::image::{
    ColourScale, Exposure, LuminanceImage, colour_map, render_false_colour, render_polar,
    write_display_png, write_false_colour_png, write_hdr, write_polar_png,
};
use std::path::Path;

fn path(dir: &Path, name: &str) -> String {
    dir.join(name).to_str().unwrap().to_string()
}

/// Names in `dir`: a write leaves its file and no temporary.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn hdr_round_trip_within_rgbe_precision() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (37, 5); // >= 8 wide: RLE scanlines
    let img = LuminanceImage::from_fn(w, h, |x, y| {
        if x == 0 {
            0.0
        } else {
            // Many decades, irregular mantissas.
            10f64.powf(-20.0 + 40.0 * (x + w * y) as f64 / (w * h) as f64)
                * (1.0 + 0.37 * (x % 3) as f64)
        }
    })
    .unwrap();
    let p = path(dir.path(), "l.hdr");
    write_hdr(&img, &p).unwrap();
    assert_eq!(names(dir.path()), ["l.hdr"]);
    let text = std::fs::read(&p).unwrap();
    let head = String::from_utf8_lossy(&text[..200]);
    assert!(head.starts_with("#?RADIANCE\n"), "{head}");
    assert!(head.contains("luminance L [cd/m^2]"), "{head}");

    let back = image::open(&p).unwrap();
    assert_eq!((back.width() as usize, back.height() as usize), (w, h));
    let rgb = back.to_rgb32f();
    let mut worst: f64 = 0.0;
    for y in 0..h {
        for x in 0..w {
            let px = rgb.get_pixel(x as u32, y as u32).0;
            assert!(px[0] == px[1] && px[1] == px[2], "grey: {px:?}");
            let (l, got) = (img.get(x, y), px[0] as f64);
            if l == 0.0 {
                assert_eq!(got, 0.0);
            } else {
                worst = worst.max((got - l).abs() / l);
            }
        }
    }
    // 8-bit mantissa rounded to nearest: 1/256 at worst (plus f32 round-off).
    assert!(worst <= 1.0 / 256.0 + 1e-6, "worst relative error {worst}");
    assert!(worst > 1e-4, "suspiciously exact: {worst}");
}

#[test]
fn display_png_maps_known_values_through_srgb() {
    let dir = tempfile::tempdir().unwrap();
    let img = LuminanceImage::new(5, 1, vec![1.0, 0.0, 0.5, 2.0, 0.001]).unwrap();
    let p = path(dir.path(), "d.png");
    write_display_png(&img, &p, Exposure::Fixed(1.0)).unwrap();
    let back = image::open(&p).unwrap();
    assert_eq!(back.color(), image::ColorType::L8);
    assert_eq!((back.width(), back.height()), (5, 1));
    // 1 -> white, 0 -> black, 0.5 -> sRGB(0.5) = 0.7354 -> 188, clipped above 1,
    // 0.001 on the linear toe: 12.92e-3 * 255 = 3.29 -> 3.
    assert_eq!(back.to_luma8().into_raw(), vec![255, 0, 188, 255, 3]);

    write_display_png(&img, &p, Exposure::Fixed(2.0)).unwrap();
    assert_eq!(
        image::open(&p).unwrap().to_luma8().into_raw()[..3],
        [255, 0, 255]
    );
}

#[test]
fn display_png_auto_exposure_puts_the_99th_percentile_at_white() {
    let dir = tempfile::tempdir().unwrap();
    // 200 pixels 1..=200 cd/m^2: the 99th percentile (nearest rank 198) is 198.
    let img = LuminanceImage::from_fn(20, 10, |x, y| (1 + x + 20 * y) as f64).unwrap();
    let p = path(dir.path(), "auto.png");
    write_display_png(&img, &p, Exposure::Auto).unwrap();
    let g = image::open(&p).unwrap().to_luma8().into_raw();
    assert_eq!(g[197], 255);
    assert_eq!(g[196], 254); // 197/198 -> just below white
    assert_eq!(g[98], 188); // 99/198 = 0.5
}

#[test]
fn false_colour_uses_the_scale_ends_and_matches_the_render() {
    let dir = tempfile::tempdir().unwrap();
    let scale = ColourScale {
        min: 10.0,
        max: 1000.0,
        log: true,
    };
    // Left half at min, right half at max; corners beyond both ends.
    let img = LuminanceImage::from_fn(8, 4, |x, y| match (x, y) {
        (0, 3) => 0.0,
        (7, 3) => 1e9,
        (x, _) if x < 4 => 10.0,
        _ => 1000.0,
    })
    .unwrap();
    let plot = render_false_colour(&img, scale).unwrap();
    let z = plot.zoom;
    assert_eq!(z, 64); // 4 rows -> 256 px
    let p = path(dir.path(), "fc.png");
    write_false_colour_png(&img, &p, scale).unwrap();
    let back = image::open(&p).unwrap().to_rgb8();
    assert_eq!(
        (back.width() as usize, back.height() as usize),
        (plot.image.width, plot.image.height)
    );
    assert!(plot.image.width > 8 * z + 40, "room for the scale bar");
    assert_eq!(back.into_raw(), plot.image.data);
    let px = |x: usize, y: usize| plot.image.pixel(x * z + z / 2, y * z + z / 2);
    assert_eq!(px(0, 0), colour_map(0.0));
    assert_eq!(px(3, 1), colour_map(0.0));
    assert_eq!(px(4, 0), colour_map(1.0));
    assert_eq!(px(0, 3), colour_map(0.0)); // below min: clamped
    assert_eq!(px(7, 3), colour_map(1.0)); // above max: clamped
    assert_ne!(colour_map(0.0), colour_map(1.0));
    // Halfway in log: 100 cd/m^2 is the middle colour.
    assert_eq!(scale.colour(100.0), colour_map(0.5));
}

#[test]
fn false_colour_scale_bar_has_label_text() {
    let img = LuminanceImage::from_fn(64, 48, |x, y| 0.5 + (x * y) as f64).unwrap();
    let scale = ColourScale::from_data(&img.l, true);
    assert_eq!(scale.max, 0.5 + 63.0 * 47.0);
    assert!((scale.min - scale.max / 1000.0).abs() < 1e-12);
    let plot = render_false_colour(&img, scale).unwrap();
    let im = &plot.image;
    let x0 = 64 * plot.zoom;
    let is_ink = |c: [u8; 3]| c.iter().all(|&v| v < 60);
    // Unit label: ink in the top rows of the bar region.
    let top_ink = (0..30)
        .flat_map(|y| (x0..im.width).map(move |x| (x, y)))
        .filter(|&(x, y)| is_ink(im.pixel(x, y)))
        .count();
    assert!(top_ink > 30, "unit label: {top_ink} ink pixels");
    // Tick labels: ink in the right half of the bar region, spread over rows.
    let xr = x0 + (im.width - x0) / 2;
    let rows_with_ink = (0..im.height)
        .filter(|&y| (xr..im.width).any(|x| is_ink(im.pixel(x, y))))
        .count();
    assert!(
        rows_with_ink > 40,
        "tick labels: {rows_with_ink} rows with ink"
    );
}

/// (theta, phi, L) on a 10-deg x 15-deg grid: L = 100 on theta 50..70 deg,
/// phi -15..15 deg; 50.5 on theta 20..40 deg, phi 75..105 deg; 1 elsewhere.
fn hemisphere_samples() -> Vec<(f64, f64, f64)> {
    let mut v = Vec::new();
    for i in 0..=9 {
        for j in 0..24 {
            let (t, p) = (10.0 * i as f64, 15.0 * j as f64);
            let dp = (p + 180.0).rem_euclid(360.0) - 180.0;
            let l = if (50.0..=70.0).contains(&t) && dp.abs() <= 15.0 {
                100.0
            } else if (20.0..=40.0).contains(&t) && (75.0..=105.0).contains(&p) {
                50.5
            } else {
                1.0
            };
            v.push((t.to_radians(), p.to_radians(), l));
        }
    }
    v
}

#[test]
fn polar_plot_puts_the_hot_spot_at_its_direction() {
    let dir = tempfile::tempdir().unwrap();
    let samples = hemisphere_samples();
    let scale = ColourScale {
        min: 1.0,
        max: 100.0,
        log: false,
    };
    let plot = render_polar(&samples, scale, "L(θ, φ) lower plane").unwrap();
    let p = path(dir.path(), "polar.png");
    write_polar_png(&p, &samples, scale, "L(θ, φ) lower plane").unwrap();
    assert_eq!(names(dir.path()), ["polar.png"]);
    let back = image::open(&p).unwrap().to_rgb8();
    assert_eq!(back.into_raw(), plot.image.data);

    let at = |t: f64, ph: f64| {
        let (x, y) = plot.pixel_at(t.to_radians(), ph.to_radians());
        plot.image.pixel(x, y)
    };
    // Off the ring and spoke lines, inside the hot cell around (60, 0) deg.
    assert_eq!(at(55.0, 8.0), colour_map(1.0));
    assert_eq!(at(65.0, -8.0), colour_map(1.0));
    // phi = 0 is to the right: the same theta at 180 deg is cold.
    let (x, y) = plot.pixel_at(55f64.to_radians(), 8f64.to_radians());
    assert!(x as f64 > plot.centre.0 + 0.5 * plot.radius);
    assert!((y as f64 - plot.centre.1).abs() < 0.3 * plot.radius);
    assert_eq!(at(55.0, 188.0), colour_map(0.0));
    // phi = 90 deg is up: the mid-valued patch shows the middle colour there.
    let (_, y) = plot.pixel_at(25f64.to_radians(), 97f64.to_radians());
    assert!((y as f64) < plot.centre.1 - 0.2 * plot.radius);
    assert_eq!(at(25.0, 97.0), colour_map(0.5));
    assert_eq!(at(25.0, 263.0), colour_map(0.0));
    // Near the rim: still coloured; a corner of the canvas: white background.
    let (x, y) = plot.pixel_at(89f64.to_radians(), 45f64.to_radians());
    assert_ne!(plot.image.pixel(x, y), [255, 255, 255]);
    assert_eq!(plot.image.pixel(2, plot.image.height - 2), [255, 255, 255]);
}

#[test]
fn bad_inputs_are_errors_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    assert!(LuminanceImage::new(2, 1, vec![1.0, f64::NAN]).is_err());
    assert!(LuminanceImage::new(2, 1, vec![1.0, -0.5]).is_err());
    assert!(LuminanceImage::new(2, 1, vec![1.0]).is_err());
    // Public fields can bypass `new`; every writer checks again.
    let bad = LuminanceImage {
        width: 2,
        height: 1,
        l: vec![1.0, f64::NAN],
    };
    let neg = LuminanceImage {
        width: 2,
        height: 1,
        l: vec![1.0, -2.0],
    };
    let ok = LuminanceImage::new(2, 1, vec![1.0, 2.0]).unwrap();
    let scale = ColourScale::from_data(&ok.l, false);
    for img in [&bad, &neg] {
        let e = write_hdr(img, &path(dir.path(), "a.hdr")).unwrap_err();
        assert!(e.to_string().contains("pixel (x=1, y=0)"), "{e}");
        assert!(write_display_png(img, &path(dir.path(), "a.png"), Exposure::Auto).is_err());
        assert!(write_false_colour_png(img, &path(dir.path(), "b.png"), scale).is_err());
    }
    assert!(write_display_png(&ok, &path(dir.path(), "c.png"), Exposure::Fixed(-1.0)).is_err());
    let flat = ColourScale {
        min: 1.0,
        max: 1.0,
        log: false,
    };
    let log0 = ColourScale {
        min: 0.0,
        max: 1.0,
        log: true,
    };
    for sc in [flat, log0] {
        assert!(write_false_colour_png(&ok, &path(dir.path(), "d.png"), sc).is_err());
    }
    let mut samples = hemisphere_samples();
    samples[5].2 = f64::NAN;
    let e = write_polar_png(&path(dir.path(), "p.png"), &samples, scale, "t").unwrap_err();
    assert!(e.to_string().contains("finite"), "{e}");
    samples[5].2 = -3.0;
    assert!(write_polar_png(&path(dir.path(), "p.png"), &samples, scale, "t").is_err());
    samples[5] = (100f64.to_radians(), 0.0, 1.0);
    assert!(write_polar_png(&path(dir.path(), "p.png"), &samples, scale, "t").is_err());
    assert!(write_polar_png(&path(dir.path(), "p.png"), &[], scale, "t").is_err());
    assert!(names(dir.path()).is_empty(), "{:?}", names(dir.path()));
    // A missing folder is a write error naming the path.
    let e = write_hdr(&ok, &path(dir.path(), "no/such/dir/x.hdr")).unwrap_err();
    assert!(e.to_string().contains("cannot write"), "{e}");
}

/// One image of each kind, into `$LUMEST_IMAGE_DEMO_DIR` when set (to look
/// at), otherwise into a temporary folder.
#[test]
fn demo_images() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = std::env::var("LUMEST_IMAGE_DEMO_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|_| tmp.path().to_path_buf());
    std::fs::create_dir_all(&dir).unwrap();
    // A lit floor seen from above: a bright spot under a lamp, falling off as cos^4.
    let (w, h) = (160, 100);
    let img = LuminanceImage::from_fn(w, h, |x, y| {
        let (u, v) = ((x as f64 - 60.0) / 40.0, (y as f64 - 45.0) / 40.0);
        300.0 / (1.0 + u * u + v * v).powi(2) + 2.0
    })
    .unwrap();
    write_hdr(&img, &path(&dir, "floor.hdr")).unwrap();
    write_display_png(&img, &path(&dir, "floor_display.png"), Exposure::Auto).unwrap();
    write_false_colour_png(
        &img,
        &path(&dir, "floor_false_colour_log.png"),
        ColourScale::from_data(&img.l, true),
    )
    .unwrap();
    write_false_colour_png(
        &img,
        &path(&dir, "floor_false_colour_linear.png"),
        ColourScale::from_data(&img.l, false),
    )
    .unwrap();
    // A hemisphere: a broad lobe near theta = 60 deg, phi = 0 over a cosine floor.
    let mut samples = Vec::new();
    for i in 0..=18 {
        for j in 0..72 {
            let (t, p) = ((5.0 * i as f64).to_radians(), (5.0 * j as f64).to_radians());
            // Angle d from the lobe's axis (theta = 60 deg, phi = 0).
            let a = 60f64.to_radians();
            let d = (t.cos() * a.cos() + t.sin() * a.sin() * p.cos())
                .clamp(-1.0, 1.0)
                .acos();
            samples.push((t, p, 40.0 * t.cos() + 500.0 * (-(d / 0.25).powi(2)).exp()));
        }
    }
    let scale = ColourScale::from_data(&samples.iter().map(|s| s.2).collect::<Vec<_>>(), true);
    write_polar_png(
        &path(&dir, "polar.png"),
        &samples,
        scale,
        "L(θ, φ) at a point of the lower plane",
    )
    .unwrap();
    for n in [
        "floor_display.png",
        "floor_false_colour_log.png",
        "floor_false_colour_linear.png",
        "polar.png",
    ] {
        image::open(dir.join(n)).unwrap();
    }
}
