//! The exact direct light of area sources and a cosine luminaire (the
//! estimator's closed forms) against independent closed forms and
//! quadrature (`lumest::reference`), as `lumest validate luminaires` runs
//! them: to 1e-10 where both are closed forms, and every tolerance far
//! below the 2 % a wrong answer would be off.

use lumest::cases::luminaires::closed_form_rows;

#[test]
fn exact_direct_light_matches_the_independent_closed_forms() {
    let dir = std::env::temp_dir().join(format!("lumest-closed-{}", std::process::id()));
    let rows = closed_form_rows(&dir).unwrap();
    assert_eq!(rows.len(), 4);
    for r in &rows {
        assert!(r.max_rel.is_finite() && r.max_rel <= r.tolerance, "{r:?}");
        assert!(r.tolerance <= 2e-4 && r.points >= 40, "{r:?}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
