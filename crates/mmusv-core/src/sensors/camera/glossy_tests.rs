//! Tests of `glossy.rs`: the blur's moments, roll and edges, the sky's lobe means, and the traced directions'
//! draws and strata.

use super::*;

/// Every pixel of a `w × h` image a sample of roughness `mss` and grazing sine `sin_g`, radiance from `value`.
fn samples(w: usize, h: usize, mss: f32, sin_g: f32, value: impl Fn(usize, usize) -> Vec3) -> Vec<Sample> {
    (0..w * h)
        .map(|i| Sample {
            x: (i % w) as u32,
            y: (i / w) as u32,
            value: value(i % w, i / w),
            sky: Vec3::ZERO,
            lobe_sky: Vec3::ZERO,
            mss,
            sin_grazing: sin_g,
        })
        .collect()
}

/// The blurred image at every pixel centre.
fn image(b: &Blurred, w: usize, h: usize) -> Vec<Vec3> {
    (0..w * h).map(|i| b.at((i % w) as f32 + 0.5, (i / w) as f32 + 0.5).unwrap_or(Vec3::ZERO)).collect()
}

/// Mean and standard deviation of the image's first channel along x and y, as a distribution.
fn moments(img: &[Vec3], w: usize) -> ([f64; 2], [f64; 2]) {
    let total: f64 = img.iter().map(|c| f64::from(c.x)).sum();
    let mut m = [0f64; 2];
    for (i, c) in img.iter().enumerate() {
        m[0] += (i % w) as f64 * f64::from(c.x) / total;
        m[1] += (i / w) as f64 * f64::from(c.x) / total;
    }
    let mut v = [0f64; 2];
    for (i, c) in img.iter().enumerate() {
        v[0] += ((i % w) as f64 - m[0]).powi(2) * f64::from(c.x) / total;
        v[1] += ((i / w) as f64 - m[1]).powi(2) * f64::from(c.x) / total;
    }
    (m, [v[0].sqrt(), v[1].sqrt()])
}

#[test]
fn a_point_spreads_into_the_lobe_of_its_slopes() {
    // mss 0.02 at 500 px/rad, sin γ = 0.3: about 2σ₁ f = 100 px down and 2σ₁ f sin γ ≈ 30 px across (the
    // first-order lobe); the lobe's own moments below.
    // (Tall enough that the image's edges, where each pixel's mean is over fewer neighbours, are 6 σ away.)
    let (w, h) = (400, 1200);
    let s = samples(w, h, 0.02, 0.3, |x, y| if (x, y) == (200, 600) { Vec3::new(1.0, 2.0, 3.0) } else { Vec3::ZERO });
    let [lx, ly, off] = lobe_px(0.02, 0.3, 500.0);
    // (Down the image the lobe is narrower than the first-order 100 px: at 17° below the horizontal, part of it
    // would leave under the horizon and is masked.)
    assert!((lx - 30.0).abs() < 3.0 && ly > 70.0 && ly < 100.0 && off.abs() < 10.0, "{lx} {ly} {off}");
    let Some(b) = blur(w, h, 500.0, 1, 0.0, &s) else { panic!("no blur") };
    let out = image(&b, w, h);
    let (m, sd) = moments(&out, w);
    // Each pixel is a normalised mean over its share of the lobe around it (SCREEN_SHARE of its spread; the
    // traced directions carry the rest and the lobe's offset, `lobe_ray`): a unit point spreads into that
    // kernel mirrored (every pixel whose kernel reaches it), with its spread (within the discretisation of
    // the boxes and the coarse grid) and no offset.
    let (kx, ky) = (f64::from(SCREEN_SHARE * lx), f64::from(SCREEN_SHARE * ly));
    assert!((m[0] - 200.0).abs() < 2.0 && (m[1] - 600.0).abs() < 3.0, "centre {m:?}");
    assert!((sd[0] - kx).abs() < 1.5, "horizontal σ {} px, want {kx}", sd[0]);
    assert!((sd[1] - ky).abs() < 3.0, "vertical σ {} px, want {ky}", sd[1]);
    // The channels stay in proportion, and what is spread is what was there (a sum over the pixels).
    let total: Vec3 = out.iter().copied().sum();
    assert!((total.y / total.x - 2.0).abs() < 1e-3 && (total.z / total.x - 3.0).abs() < 1e-3);
    assert!((total.x - 1.0).abs() < 0.03, "total {}", total.x);
}

#[test]
fn a_rolled_camera_spreads_along_the_world_vertical_it_shows() {
    // The same point as above, the world's vertical turned by 0.3 rad in the image: the spread's long axis is
    // the image's (−sin 0.3, cos 0.3), and its two spreads are the lobe's.
    let (w, h, roll) = (900usize, 900usize, 0.3f32);
    let s = samples(w, h, 0.02, 0.3, |x, y| if (x, y) == (450, 450) { Vec3::ONE } else { Vec3::ZERO });
    let Some(b) = blur(w, h, 500.0, 1, roll, &s) else { panic!("no blur") };
    let out = image(&b, w, h);
    let total: f64 = out.iter().map(|c| f64::from(c.x)).sum();
    let mean = |f: &dyn Fn(f64, f64) -> f64| {
        out.iter().enumerate().map(|(i, c)| f((i % w) as f64, (i / w) as f64) * f64::from(c.x)).sum::<f64>() / total
    };
    let (mx, my) = (mean(&|x, _| x), mean(&|_, y| y));
    let sxx = mean(&|x, _| (x - mx).powi(2));
    let syy = mean(&|_, y| (y - my).powi(2));
    let sxy = mean(&|x, y| (x - mx) * (y - my));
    // Principal axis of the covariance, and the spreads along and across it.
    let angle = 0.5 * (2.0 * sxy).atan2(syy - sxx);
    let want = f64::from(-roll);
    assert!((angle - want).abs() < 0.03, "long axis at {angle} rad from the columns, want {want}");
    let [lx, ly, _] = lobe_px(0.02, 0.3, 500.0);
    let (c, sn) = (angle.cos(), angle.sin());
    let along = (syy * c * c + sxx * sn * sn + 2.0 * sxy * sn * c).sqrt();
    let across = (sxx * c * c + syy * sn * sn - 2.0 * sxy * sn * c).sqrt();
    let (kx, ky) = (f64::from(SCREEN_SHARE * lx), f64::from(SCREEN_SHARE * ly));
    assert!((along - ky).abs() < 4.0, "along {along}, want {ky}");
    assert!((across - kx).abs() < 2.0, "across {across}, want {kx}");
}

#[test]
fn the_traced_directions_and_the_blur_together_spread_as_the_lobe() {
    // The directions `lobe_ray` draws over the unit square (a fine grid standing for the strata of many
    // seeds): their mean offset is the lobe's, their spreads `√(1 − κ²)` of its; with the blur's `κ` of it,
    // the variances add up to the lobe's.
    let (mss, sin_g) = (0.02f32, 0.3f32);
    let [de, se, sa] = rough_water::lobe(sin_g, mss.sqrt());
    let e0 = sin_g.asin(); // a flat surface: the mirror direction rises as steeply as the view falls
    let mirror = Vec3::new(e0.cos(), 0.0, e0.sin());
    let n = 256;
    let (mut sum, mut sq) = ([0f64; 2], [0f64; 2]);
    for i in 0..n {
        for j in 0..n {
            let u = [(i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32];
            let r = lobe_ray(mirror, mss, sin_g, u);
            let off = [f64::from(r.z.asin() - e0), f64::from(r.y.atan2(r.x))];
            for k in 0..2 {
                sum[k] += off[k];
                sq[k] += off[k] * off[k];
            }
        }
    }
    let count = (n * n) as f64;
    let mean = [sum[0] / count, sum[1] / count];
    let sd = [0, 1].map(|k| (sq[k] / count - mean[k] * mean[k]).sqrt());
    let q = f64::from((1.0 - SCREEN_SHARE * SCREEN_SHARE).sqrt());
    assert!((mean[0] - f64::from(de)).abs() < 2e-3 && mean[1].abs() < 1e-4, "mean {mean:?}, want {de}");
    assert!((sd[0] / (q * f64::from(se)) - 1.0).abs() < 0.03, "elevation σ {}, want {}", sd[0], q * f64::from(se));
    assert!((sd[1] / (q * f64::from(sa)) - 1.0).abs() < 0.03, "azimuth σ {}, want {}", sd[1], q * f64::from(sa));
    let total = (sd[0].powi(2) + f64::from(SCREEN_SHARE * se).powi(2)).sqrt();
    assert!((total / f64::from(se) - 1.0).abs() < 0.03, "drawn and blurred {total}, lobe {se}");
}

#[test]
fn each_four_by_four_blocks_draw_the_whole_set_of_strata() {
    for (spacing, seed) in [(1u32, 0u64), (2, 7), (4, 123)] {
        let points: Vec<[f32; 2]> = (0..4u32)
            .flat_map(|by| (0..4u32).map(move |bx| (bx, by)))
            .map(|(bx, by)| stratum(bx * spacing + 8 * spacing, by * spacing, spacing, seed))
            .collect();
        // One point in every sixteenth of each axis (a Latin square of strata, shifted by the seed's rotation).
        for axis in 0..2 {
            let mut cells: Vec<u32> = points.iter().map(|p| (p[axis] * 16.0) as u32).collect();
            cells.sort_unstable();
            cells.dedup();
            assert_eq!(cells.len(), 16, "spacing {spacing}, seed {seed}, axis {axis}: {points:?}");
        }
        // Pixels of one block share their block's point.
        assert_eq!(stratum(spacing - 1, spacing - 1, spacing, seed), stratum(0, 0, spacing, seed));
    }
    assert_ne!(stratum(0, 0, 2, 1), stratum(0, 0, 2, 2));
}

#[test]
fn a_flat_layer_stays_flat_and_other_pixels_neither_give_nor_take() {
    let (w, h) = (64, 48);
    // A hull in the middle: not water, so no samples there (whatever it looks like, it must not leak in).
    let hull = |x: usize, y: usize| (20..40).contains(&x) && (10..20).contains(&y);
    let s: Vec<Sample> = samples(w, h, 0.01, 0.2, |_, _| Vec3::new(5.0, 6.0, 7.0))
        .into_iter()
        .filter(|s| !hull(s.x as usize, s.y as usize))
        .collect();
    let Some(b) = blur(w, h, 200.0, 1, 0.0, &s) else { panic!("no blur") };
    for (i, c) in image(&b, w, h).iter().enumerate() {
        if !hull(i % w, i / w) {
            assert!((*c - Vec3::new(5.0, 6.0, 7.0)).abs().max_element() < 1e-3, "pixel {i}: {c:?}");
        }
    }
    // Traced every other pixel (as at standard quality): the same.
    let sparse: Vec<Sample> = s.iter().filter(|p| p.x % 2 == 0 && p.y % 2 == 0).copied().collect();
    let Some(b) = blur(w, h, 200.0, 2, 0.0, &sparse) else { panic!("no blur") };
    for (i, c) in image(&b, w, h).iter().enumerate() {
        if !hull(i % w, i / w) {
            assert!((*c - Vec3::new(5.0, 6.0, 7.0)).abs().max_element() < 1e-3, "pixel {i}: {c:?}");
        }
    }
    assert!(blur(w, h, 200.0, 1, 0.0, &[]).is_none());
}

#[test]
fn the_sky_is_read_from_its_lobe_means_whatever_the_lobe_reaches() {
    // Reflections that all leave for the sky (value = sky along them) over water whose lobe is far wider than
    // the image (a narrow lens): each place reads the sky's lobe mean given with its samples, not the mirror
    // directions' sky the screen-space spread would average near the edges. A smooth lobe mean (linear down
    // the image) is read back exactly at the cells' centres and within a cell's change between them.
    let (w, h) = (32, 24);
    let lobe_sky = |y: usize| Vec3::new(100.0 + y as f32, 200.0, 300.0 - 2.0 * y as f32);
    let mirror = |x: usize, y: usize| Vec3::new(50.0 + x as f32, 80.0 + 3.0 * y as f32, 900.0);
    let s: Vec<Sample> = samples(w, h, 0.05, 0.5, |_, _| Vec3::ZERO)
        .into_iter()
        .map(|p| {
            let (x, y) = (p.x as usize, p.y as usize);
            Sample { value: mirror(x, y), sky: mirror(x, y), lobe_sky: lobe_sky(y), ..p }
        })
        .collect();
    let Some(b) = blur(w, h, 3000.0, 1, 0.0, &s) else { panic!("no blur") };
    for (i, c) in image(&b, w, h).iter().enumerate() {
        let want = lobe_sky(i / w);
        assert!((*c - want).abs().max_element() < 2.0 * b.dy as f32 + 1e-3, "pixel {i}: {c:?}, want {want:?}");
    }
    // A reflected hull (brighter than an even sky by 1000 in a block) is spread around it.
    let hull = |x: usize, y: usize| (12..20).contains(&x) && (8..14).contains(&y);
    let even = Vec3::new(200.0, 300.0, 400.0);
    let with_hull = |hull_value: Vec3| -> Vec<Sample> {
        s.iter()
            .map(|p| {
                let (x, y) = (p.x as usize, p.y as usize);
                let value = if hull(x, y) { hull_value } else { even };
                Sample { value, sky: even, lobe_sky: even, ..*p }
            })
            .collect()
    };
    let Some(bh) = blur(w, h, 3000.0, 1, 0.0, &with_hull(even + Vec3::splat(1000.0))) else { panic!("no blur") };
    let extra: f32 = image(&bh, w, h).iter().map(|c| c.x - even.x).sum::<f32>() / (w * h) as f32;
    // The spread is a normalised mean over the whole image here and, down it, over the edge rows read again
    // past its top and bottom as far as it is tall (the lobe reaches past it every way): every pixel gets the
    // hull's share, 8 of 32 columns and 6 of 24 + 2 × 24 rows of 1000.
    let want = 1000.0 * (8.0 / 32.0) * (6.0 / 72.0);
    assert!((extra - want).abs() < 0.05 * want, "{extra}, want {want}");
    // A black hull hiding a sky far brighter than the lobe's mean there (dusk: the afterglow low in the mirror,
    // the lobe reaching up into darker sky): the reflection darkens but never goes below zero (the sum of the
    // lobe's mean and the spread difference did, and showed black and pure blue water).
    let dusk: Vec<Sample> = with_hull(Vec3::ZERO)
        .into_iter()
        .map(|p| Sample { sky: Vec3::new(5000.0, 3000.0, 900.0), lobe_sky: Vec3::new(500.0, 400.0, 300.0), ..p })
        .map(|p| if hull(p.x as usize, p.y as usize) { p } else { Sample { value: p.sky, ..p } })
        .collect();
    let Some(bd) = blur(w, h, 3000.0, 1, 0.0, &dusk) else { panic!("no blur") };
    for (i, c) in image(&bd, w, h).iter().enumerate() {
        assert!(c.min_element() >= 0.0 && c.max_element() <= 500.0 + 1e-3, "pixel {i}: {c:?}");
    }
}

#[test]
fn calmer_water_and_a_wider_view_spread_less() {
    assert!(lobe_px(0.003, 0.5, 320.0)[1] < lobe_px(0.046, 0.5, 320.0)[1]);
    assert!(lobe_px(0.01, 0.5, 100.0)[1] < lobe_px(0.01, 0.5, 320.0)[1]);
    // Near the horizon the horizontal spread narrows, and the lobe's centre drops below the pixel.
    assert!(lobe_px(0.01, 0.02, 320.0)[0] < 0.3 * lobe_px(0.01, 0.5, 320.0)[0]);
    assert!(lobe_px(0.01, 0.02, 320.0)[2] > 10.0);
    assert_eq!(decimation(1.0, 1), [1, 1]);
    assert_eq!(decimation(1.0, 2), [2, 2]);
    assert_eq!(decimation(10.0, 1), [1, 2]);
    assert_eq!(decimation(20.0, 1), [2, 4]);
    assert_eq!(decimation(100.0, 2), [4, 8]);
}
