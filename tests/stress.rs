//! The quick subset of the stress matrix (`lumest validate stress --quick`)
//! through the library: every family runs, every number is finite and no
//! row fails. Each case runs a fixed number of chains, so the rows are
//! bit-identical for any thread count.

use lumest::commands::stress::{Budget, StressOptions, Verdict, stress_rows};

#[test]
fn quick_stress_matrix_has_no_failures() {
    let opts = StressOptions {
        quick: true,
        budget: Budget::Tuned,
        seed: 1,
        threads: 2,
        // Stricter than the command's 0.01: one false alarm in a thousand
        // per change of the solver, rather than one in a hundred.
        alpha: 1e-3,
    };
    let report = stress_rows(&opts);
    for family in [
        "sobolev",
        "integrating-sphere",
        "near-wall",
        "near-source",
        "scaled",
    ] {
        assert!(
            report.rows.iter().any(|r| r.family == family),
            "no rows for family {family}"
        );
    }
    for r in &report.rows {
        let what = format!("{} / {} / {}", r.family, r.case, r.point);
        assert!(r.chains > 0 && r.batches >= 32, "{what}: {}", r.note);
        for (name, v) in [
            ("estimate", Some(r.estimate)),
            ("std_error", Some(r.std_error)),
            ("direct", Some(r.direct)),
            ("exact", r.exact),
            ("reference", r.reference),
            ("reference std_error", Some(r.reference_std_error)),
            ("rel_err", r.rel_err),
            ("z", r.z),
        ] {
            assert!(
                v.is_none_or(f64::is_finite),
                "{what}: {name} = {v:?} is not finite"
            );
        }
        assert!(
            r.reference.is_some() && r.z.is_some(),
            "{what}: no reference"
        );
        assert_ne!(r.verdict, Verdict::Fail, "{what}: {}", r.note);
        // The far field between reflecting planes is missed by the plain
        // local estimate; the `sparse` check must say so.
        // Its remedy, `--near-radius auto`, must not be sparse.
        if r.family == "sobolev" && r.point.contains("r=10000") {
            let remedy = r.case.contains("near-radius=auto");
            assert_eq!(
                !remedy,
                r.flag.contains("sparse"),
                "{what}: flag {}",
                r.flag
            );
        }
    }
    assert!(
        report.rows.iter().any(|r| r.point.contains("r=10000")),
        "the quick subset has no far-field row"
    );
}
