//! Tests of the slab simulator against closed forms, MCML and adding-doubling.

use super::*;

pub(crate) fn one_layer(mua: f64, mus: f64, g: f64, n: f64, d: f64, photons: u64) -> SlabConfig {
    SlabConfig {
        layers: vec![SlabLayer {
            medium: Medium::new("", mua, mus, n, PhaseFunction::HenyeyGreenstein { g }).unwrap(),
            thickness: d,
        }],
        n_above: 1.0,
        n_below: 1.0,
        incidence: Incidence::Normal,
        estimator: Estimator::Analog,
        n_photons: photons,
        seed: 1,
        band: 0,
        radial: None,
        angular_bins: None,
        window: None,
        backing_orders: None,
    }
}

fn run(cfg: &SlabConfig) -> SlabResult {
    simulate(cfg, &Control::new()).unwrap()
}

#[test]
fn energy_is_conserved_exactly_by_both_estimators() {
    for est in [Estimator::Analog, Estimator::Weighted] {
        for inc in [Incidence::Normal, Incidence::Diffuse, Incidence::Angle(0.7)] {
            let mut cfg = one_layer(1.0, 9.0, 0.75, 1.4, 0.2, 20_000);
            cfg.estimator = est;
            cfg.incidence = inc;
            let r = run(&cfg);
            let sum = r.values[TOT_R] + r.values[TOT_T] + r.values[ABS];
            assert!((sum - 1.0).abs() < 1e-9, "{est:?} {inc:?}: {sum}");
            let parts = r.values[SPEC] + r.values[DIFF_R];
            assert!((parts - r.values[TOT_R]).abs() < 1e-12);
            let per_layer: f64 = r.absorbed_per_layer.iter().sum();
            assert!((per_layer - r.values[ABS]).abs() < 1e-12);
        }
    }
}

#[test]
fn same_seed_same_numbers_for_any_thread_count() {
    // several full batches and a partial one
    let cfg = one_layer(0.5, 20.0, 0.9, 1.5, 1.0, 67 * batch_size(20_000) + 17);
    let pool1 = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let pool3 = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap();
    let a = pool1.install(|| run(&cfg));
    let b = pool3.install(|| run(&cfg));
    assert_eq!(a, b);
    let mut other = cfg.clone();
    other.seed = 2;
    assert_ne!(run(&other).values, a.values);
}

/// Non-scattering, non-absorbing slab: two incoherent Fresnel surfaces give
/// R = r + (1−r)² r / (1 − r²) (docs/explanation/tooth-optics.md §7: 0.10853 for n = 1.63).
#[test]
fn clear_slab_matches_two_surface_fresnel() {
    for est in [Estimator::Analog, Estimator::Weighted] {
        let mut cfg = one_layer(0.0, 0.0, 0.0, 1.63, 1.0, 200_000);
        cfg.estimator = est;
        let res = run(&cfg);
        let r = ((1.63f64 - 1.0) / 2.63).powi(2);
        let r_tot = r + (1.0 - r).powi(2) * r / (1.0 - r * r);
        assert!((r_tot - 0.10853).abs() < 1e-5);
        let tol = 4.0 * res.stderr[TOT_R] + 1e-12;
        assert!(
            (res.values[TOT_R] - r_tot).abs() < tol,
            "{est:?} {:?}",
            res.values
        );
        assert_eq!(res.values[DIFF_T], 0.0);
        assert!((res.values[UNSC_T] - (1.0 - r_tot)).abs() < tol);
    }
}

/// Pure absorber, index matched: Beer–Lambert T = exp(−μa d).
#[test]
fn absorber_follows_beer_lambert() {
    let res = run(&one_layer(2.0, 0.0, 0.0, 1.0, 0.5, 100_000));
    let t = (-1.0f64).exp();
    assert!((res.values[UNSC_T] - t).abs() < 4.0 * res.stderr[UNSC_T]);
    assert_eq!(res.values[TOT_R], 0.0);
}

#[test]
fn profiles_add_up_to_the_totals() {
    let mut cfg = one_layer(1.0, 9.0, 0.75, 1.0, 0.2, 50_000);
    cfg.radial = Some((400, 40.0));
    cfg.angular_bins = Some(30);
    let r = run(&cfg);
    let dr = 40.0 / 400.0;
    let integ: f64 = r
        .radial_reflectance
        .iter()
        .enumerate()
        .map(|(i, x)| x * PI * dr * dr * ((i + 1) * (i + 1) - i * i) as f64)
        .sum();
    assert!((integ - r.values[DIFF_R]).abs() < 1e-3);
    let ang: f64 = r.angular_transmittance.iter().sum();
    assert!((ang - r.values[TOT_T]).abs() < 1e-12);
}

#[test]
fn bad_input_is_refused_with_the_field_named() {
    let mut cfg = one_layer(1.0, 9.0, 0.75, 1.0, 0.2, 10);
    cfg.layers[0].thickness = 0.0;
    let e = simulate(&cfg, &Control::new()).unwrap_err().to_string();
    assert!(e.contains("layers[0].thickness"), "{e}");
    let mut cfg = one_layer(1.0, 9.0, 0.75, 1.0, 0.2, 0);
    assert!(simulate(&cfg, &Control::new())
        .unwrap_err()
        .to_string()
        .contains("photons"));
    cfg.n_photons = 10;
    cfg.layers[0].medium.sigma_a = -1.0;
    let e = simulate(&cfg, &Control::new()).unwrap_err().to_string();
    assert!(e.contains("layers[0].mua"), "{e}");
    cfg.layers[0].medium.sigma_a = 1.0;
    cfg.n_below = 0.5;
    assert!(simulate(&cfg, &Control::new())
        .unwrap_err()
        .to_string()
        .contains("n_below"));
}

fn windowed(a: f64, b: f64, backing: f64, photons: u64) -> SlabConfig {
    let mut cfg = one_layer(0.05, 6.0, 0.9, 1.63, 1.0, photons);
    cfg.estimator = Estimator::Weighted;
    cfg.window = Some(Window {
        illuminated_radius: a,
        illuminated_inner_radius: 0.0,
        viewed_radius: b,
        viewed_inner_radius: 0.0,
        specimen_radius: f64::INFINITY,
        backing,
        cone: None,
    });
    cfg
}

fn w(r: &SlabResult, k: usize) -> (f64, f64) {
    (r.window[k], r.window_stderr[k])
}

/// Viewed + outside the window + rim + into the backing + absorbed = 1 per photon.
#[test]
fn window_ledger_closes_for_both_estimators() {
    for est in [Estimator::Analog, Estimator::Weighted] {
        for (backing, rim) in [(0.0, f64::INFINITY), (0.9, f64::INFINITY), (0.5, 2.0)] {
            let mut cfg = windowed(1.5, 1.0, backing, 20_000);
            cfg.estimator = est;
            cfg.window.as_mut().unwrap().specimen_radius = rim;
            let r = run(&cfg);
            let sum = r.window[instrument::VIEWED_R]
                + r.window[instrument::OUTSIDE_R]
                + r.window[instrument::RIM]
                + r.values[TOT_T]
                + r.values[ABS];
            assert!((sum - 1.0).abs() < 1e-9, "{est:?} {backing} {rim}: {sum}");
            let top = r.window[instrument::VIEWED_R] + r.window[instrument::OUTSIDE_R];
            assert!((top - r.values[TOT_R]).abs() < 1e-9);
            assert_eq!(r.window[instrument::RIM] > 0.0, rim.is_finite());
        }
    }
}

/// A backing inside the walk against the adding formula over runs without it,
/// R = R1 + T1 Rb T2 / (1 − Rb R2) (exact for an infinite slab on a Lambertian backing).
#[test]
fn backing_inside_the_walk_matches_the_adding_formula() {
    let rb = 0.8;
    let big = windowed(1e6, f64::INFINITY, rb, 200_000);
    let inside = run(&big);
    let mut top = one_layer(0.05, 6.0, 0.9, 1.63, 1.0, 200_000);
    top.estimator = Estimator::Weighted;
    let a = run(&top);
    let mut below = top.clone();
    below.incidence = Incidence::Diffuse;
    below.band = 1;
    let b = run(&below);
    let (r1, t1, r2, t2) = (
        a.values[TOT_R],
        a.values[TOT_T],
        b.values[TOT_R],
        b.values[TOT_T],
    );
    let adding = r1 + t1 * rb * t2 / (1.0 - rb * r2);
    let k = 1.0 / (1.0 - rb * r2);
    let se = ((a.stderr[TOT_R]).powi(2)
        + (t2 * rb * k * a.stderr[TOT_T]).powi(2)
        + (t1 * rb * k * b.stderr[TOT_T]).powi(2)
        + (t1 * rb * t2 * rb * k * k * b.stderr[TOT_R]).powi(2))
    .sqrt();
    let (v, v_se) = w(&inside, instrument::VIEWED_R);
    let tol = 4.0 * (se * se + v_se * v_se).sqrt();
    assert!(
        (v - adding).abs() < tol,
        "inside {v} adding {adding} ± {tol}"
    );
    // and the backing matters by far more than the tolerance
    assert!(v - r1 > 20.0 * tol, "{v} vs {r1}");
}

/// Reciprocity: swapping the lit and the viewed radii leaves the reading
/// (viewed power / an ideal white's) unchanged.
#[test]
fn swapping_lit_and_viewed_radii_gives_the_same_reading() {
    let reading = |a: f64, b: f64, band: u64| {
        let mut cfg = windowed(a, b, 0.5, 400_000);
        cfg.band = band;
        let r = run(&cfg);
        let f = cfg.window.unwrap().white_fraction();
        let (v, se) = w(&r, instrument::VIEWED_R);
        (v / f, se / f)
    };
    let (x, sx) = reading(3.0, 1.0, 0);
    let (y, sy) = reading(1.0, 3.0, 1);
    assert!(
        (x - y).abs() < 4.0 * (sx * sx + sy * sy).sqrt(),
        "{x} ± {sx} vs {y} ± {sy}"
    );
    // edge loss is real here: the reading is well below the infinite slab's
    let (inf, _) = reading(1e6, f64::INFINITY, 2);
    assert!(inf - x > 10.0 * sx, "{inf} vs {x}");
}

/// A cone over the whole hemisphere reads as the plain window; a ring reads a
/// Lambertian-normalised radiance factor, near the hemispherical one for a diffuse slab.
#[test]
fn detector_cone_normalises_by_its_lambertian_fraction() {
    let mut cfg = windowed(1.0, 1.0, 0.0, 100_000);
    cfg.window.as_mut().unwrap().cone = Some((0.0, 0.5 * PI));
    let r = run(&cfg);
    assert!((r.window[instrument::VIEWED_CONE] - r.window[instrument::VIEWED_R]).abs() < 1e-12);
    // a thick white diffuser: exitance close to Lambertian
    let mut cfg = one_layer(0.0, 50.0, 0.0, 1.0, 20.0, 100_000);
    cfg.window = Some(Window {
        illuminated_radius: 1e6,
        illuminated_inner_radius: 0.0,
        viewed_radius: f64::INFINITY,
        viewed_inner_radius: 0.0,
        specimen_radius: f64::INFINITY,
        backing: 0.0,
        cone: Some((40f64.to_radians(), 50f64.to_radians())),
    });
    let r = run(&cfg);
    let (cone, se) = w(&r, instrument::VIEWED_CONE);
    let hemi = r.window[instrument::VIEWED_R];
    assert!(hemi > 0.9, "{hemi}");
    // a semi-infinite isotropic scatterer is not exactly Lambertian: within 5 %
    assert!(
        (cone / hemi - 1.0).abs() < 0.05 + 4.0 * se,
        "{cone} vs {hemi}"
    );
}

#[test]
fn window_off_leaves_the_numbers_unchanged() {
    let cfg = one_layer(0.5, 20.0, 0.9, 1.5, 1.0, 10_000);
    let plain = run(&cfg);
    assert_eq!(plain.window, [0.0; 6]);
    let mut with = cfg.clone();
    with.window = Some(Window {
        illuminated_radius: 0.0,
        illuminated_inner_radius: 0.0,
        viewed_radius: f64::INFINITY,
        viewed_inner_radius: 0.0,
        specimen_radius: f64::INFINITY,
        backing: 0.0,
        cone: None,
    });
    let r = run(&with);
    assert_eq!(r.values, plain.values);
    assert!((r.window[instrument::VIEWED_R] - plain.values[TOT_R]).abs() < 1e-12);
}

#[test]
fn cancellation_stops_the_run() {
    let cfg = one_layer(0.01, 100.0, 0.9, 1.5, 10.0, 10_000_000);
    let c = Control::new();
    c.cancel();
    assert_eq!(simulate(&cfg, &c).unwrap_err(), Error::Cancelled);
}

/// A two-layer stack through a 3 mm window, for the backing-order tests.
fn two_layer_windowed(backing: f64, orders: Option<BackingOrders>, seed: u64) -> SlabConfig {
    let mut cfg = one_layer(0.02, 12.0, 0.9, 1.6, 0.6, 40_000);
    cfg.layers.push(SlabLayer {
        medium: Medium::new(
            "",
            0.05,
            20.0,
            1.54,
            PhaseFunction::HenyeyGreenstein { g: 0.93 },
        )
        .unwrap(),
        thickness: 0.9,
    });
    cfg.estimator = Estimator::Weighted;
    cfg.seed = seed;
    cfg.window = Some(Window {
        illuminated_radius: 1.5,
        illuminated_inner_radius: 0.0,
        viewed_radius: 1.5,
        viewed_inner_radius: 0.0,
        specimen_radius: f64::INFINITY,
        backing,
        cone: None,
    });
    cfg.backing_orders = orders;
    cfg
}

/// Σ_k V_k R_b^k of one window key, and its standard error from the batches' spread.
fn polynomial(res: &SlabResult, orders: usize, key: usize, rb: f64) -> (f64, f64) {
    let keys = instrument::WINDOW_KEYS.len();
    let per_batch: Vec<f64> = res
        .order_sums
        .chunks(orders * keys)
        .zip(&res.batch_photons)
        .map(|(b, &n)| {
            (0..orders)
                .map(|k| b[k * keys + key] * rb.powi(k as i32))
                .sum::<f64>()
                / n as f64
        })
        .collect();
    let total: u64 = res.batch_photons.iter().sum();
    let mean: f64 = per_batch
        .iter()
        .zip(&res.batch_photons)
        .map(|(x, &n)| x * n as f64)
        .sum::<f64>()
        / total as f64;
    let m = per_batch.len() as f64;
    let var = per_batch
        .iter()
        .zip(&res.batch_photons)
        .map(|(x, &n)| ((x - mean) * n as f64 / total as f64).powi(2))
        .sum::<f64>()
        * m
        / (m - 1.0);
    (mean, var.sqrt())
}

#[test]
fn backing_orders_reproduce_separate_backing_runs() {
    // one walk tallied by backing order against a run per backing (independent seeds); a
    // backing never simulated (0.5) is predicted by the same polynomial
    let orders = BackingOrders {
        max_order: 64,
        survival: 0.9,
        past_rim_only: false,
    };
    let poly = run(&two_layer_windowed(0.0, Some(orders), 11));
    assert!(poly.truncated < 1e-6, "truncated {}", poly.truncated);
    for rb in [0.0, 0.5, 0.9] {
        let direct = run(&two_layer_windowed(rb, None, 12));
        for key in [instrument::VIEWED_R, instrument::OUTSIDE_R] {
            let (v, s) = polynomial(&poly, 65, key, rb);
            let (d, sd) = (direct.window[key], direct.window_stderr[key]);
            let z = (v - d) / s.hypot(sd);
            assert!(
                z.abs() < 4.0,
                "rb {rb} key {key}: {v} ± {s} against {d} ± {sd}"
            );
        }
    }
    // the transmitted tally of order 0 is the reading of the transmitted light (backing 0)
    let (t0, s0) = polynomial(&poly, 65, instrument::VIEWED_T, 0.0);
    let direct = run(&two_layer_windowed(0.0, None, 13));
    let (d, sd) = (
        direct.window[instrument::VIEWED_T],
        direct.window_stderr[instrument::VIEWED_T],
    );
    assert!(
        ((t0 - d) / s0.hypot(sd)).abs() < 4.0,
        "{t0} ± {s0} against {d} ± {sd}"
    );
}

#[test]
fn ring_windows_with_backing_orders_reproduce_brute_force_runs() {
    // a fibre probe: a lit ring read at the centre, and a lit centre read over a ring. The
    // backing-order walk integrates the entry point out (overlap_fraction of the rings); the
    // plain walk samples it over the ring and counts exits inside the window
    let orders = BackingOrders {
        max_order: 64,
        survival: 0.9,
        past_rim_only: false,
    };
    for (a0, a, b0, b) in [(1.0, 1.5, 0.0, 0.6), (0.0, 0.6, 1.0, 1.5)] {
        let ring = |cfg: &mut SlabConfig| {
            let w = cfg.window.as_mut().unwrap();
            w.illuminated_inner_radius = a0;
            w.illuminated_radius = a;
            w.viewed_inner_radius = b0;
            w.viewed_radius = b;
        };
        let mut cfg = two_layer_windowed(0.0, Some(orders), 21);
        ring(&mut cfg);
        let poly = run(&cfg);
        for rb in [0.0, 0.9] {
            let mut direct = two_layer_windowed(rb, None, 22);
            ring(&mut direct);
            direct.n_photons = 200_000;
            let direct = run(&direct);
            // the transmitted reading is the walk over a black backing (order 0)
            let keys: &[usize] = if rb == 0.0 {
                &[
                    instrument::VIEWED_R,
                    instrument::OUTSIDE_R,
                    instrument::VIEWED_T,
                ]
            } else {
                &[instrument::VIEWED_R, instrument::OUTSIDE_R]
            };
            for &key in keys {
                let (v, s) = polynomial(&poly, 65, key, rb);
                let (d, sd) = (direct.window[key], direct.window_stderr[key]);
                assert!(d > 0.0 && v > 0.0, "{a0} {a} {b0} {b} key {key}: {v} {d}");
                let z = (v - d) / s.hypot(sd);
                assert!(
                    z.abs() < 4.0,
                    "rings {a0} {a} {b0} {b} rb {rb} key {key}: {v} ± {s} against {d} ± {sd}"
                );
            }
        }
    }
}

#[test]
fn backing_orders_are_refused_without_a_window_or_out_of_range() {
    let mut cfg = one_layer(0.1, 10.0, 0.9, 1.5, 1.0, 100);
    cfg.backing_orders = Some(BackingOrders {
        max_order: 8,
        survival: 0.9,
        past_rim_only: false,
    });
    assert!(cfg.validate().unwrap_err().to_string().contains("window"));
    for (max_order, survival, field) in [
        (0, 0.9, "max_order"),
        (8, 0.0, "survival"),
        (8, 1.5, "survival"),
        (MAX_BACKING_ORDER + 1, 0.9, "max_order"),
    ] {
        let mut cfg = two_layer_windowed(
            0.0,
            Some(BackingOrders {
                max_order,
                survival,
                past_rim_only: false,
            }),
            1,
        );
        cfg.n_photons = 100;
        assert!(cfg.validate().unwrap_err().to_string().contains(field));
    }
}

#[test]
fn past_rim_tally_is_the_difference_between_infinite_and_finite_specimens() {
    // a narrow specimen (rim 2 mm around a 1.5 mm window) loses much of a white backing's
    // light at its rim; the past-rim walk estimates what the rim takes, so that infinite −
    // past-rim reproduces the finite specimen (independent seeds, 4 s.e.): what the window
    // reads, what leaves outside it and what the rim itself takes
    let orders = |past_rim_only| BackingOrders {
        max_order: 64,
        survival: 0.9,
        past_rim_only,
    };
    let with_rim = |past, seed| {
        let mut cfg = two_layer_windowed(0.0, Some(orders(past)), seed);
        cfg.window.as_mut().unwrap().specimen_radius = 2.0;
        cfg
    };
    let infinite = run(&two_layer_windowed(0.0, Some(orders(false)), 31));
    let finite = run(&with_rim(false, 32));
    let past = run(&with_rim(true, 33));
    for rb in [0.0, 0.9] {
        for key in [
            instrument::VIEWED_R,
            instrument::VIEWED_T,
            instrument::OUTSIDE_R,
            instrument::RIM,
        ] {
            let (vi, si) = polynomial(&infinite, 65, key, rb);
            let (vf, sf) = polynomial(&finite, 65, key, rb);
            let (vp, sp) = polynomial(&past, 65, key, rb);
            if rb > 0.0 && key == instrument::VIEWED_R {
                assert!(
                    vi - vf > 4.0 * si.hypot(sf),
                    "rim effect too small: {vi} {vf}"
                );
            }
            let z = (vi - vp - vf) / si.hypot(sf).hypot(sp);
            assert!(
                z.abs() < 4.0,
                "rb {rb} key {key}: {vi} − {vp} against {vf} (z {z})"
            );
        }
    }
    // the past-rim walk tallies nothing for a specimen without a rim
    let none = run(&two_layer_windowed(0.0, Some(orders(true)), 34));
    assert!(none.order_sums.iter().all(|&v| v == 0.0));
}
