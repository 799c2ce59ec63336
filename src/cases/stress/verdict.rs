//! The verdict of a stress row: the expected flags, the z test against the
//! Sidak bound, and the known failures explained by their remedy rows (the
//! rules are in the module doc of [`crate::cases::stress`]).

use super::row::StressRow;
use crate::tally::{sidak_bound, zcheck};

/// Outcome of one row (the rules are in the module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Finite, no flag, and `|z|` within the Sidak bound.
    Pass,
    /// The row carries its expected flag ([`ExpectedFlag`]): exactly,
    /// where that flag excuses the z test (a z that means nothing there),
    /// or with no other flag but the batch checks' ([`SYMPTOMS`]) and `|z|`
    /// within the Sidak bound, where the row stays z-tested.
    ExpectedFlag,
    /// Finite and `|z|` within the Sidak bound, but the diagnostics raise a
    /// flag that is not the row's expected one: reported, not passed.
    Flagged,
    /// Not finite, an error or a panic, a failed check of the row's own,
    /// or `|z|` beyond the bound, whatever flags the row carries.
    Fail,
    /// A `Fail` of the plain local estimate that carries `near` (the check
    /// that says the plain estimate is not to be trusted there) at a point
    /// whose remedy row (the same point with the near/far split,
    /// `--near-radius`) is `Pass`.
    Explained,
}

impl Verdict {
    /// `pass`, `expected-flag`, `flagged`, `FAIL` or `explained`.
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Pass => "pass",
            Verdict::ExpectedFlag => "expected-flag",
            Verdict::Flagged => "flagged",
            Verdict::Fail => "FAIL",
            Verdict::Explained => "explained",
        }
    }

    /// Every verdict, in the order of the summaries.
    pub const ALL: [Verdict; 5] = [
        Verdict::Pass,
        Verdict::ExpectedFlag,
        Verdict::Flagged,
        Verdict::Explained,
        Verdict::Fail,
    ];
}

/// The diagnostics flag a row is expected to carry, the physical reason it
/// is expected there, and whether the row is still z-tested.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ExpectedFlag {
    /// The checks the row must raise (`;`-separated, in the order the flag
    /// string lists them).
    pub flag: &'static str,
    /// Why that check must fire on that row.
    pub reason: &'static str,
    /// `false`: the flag, alone and exactly, excuses the row from the z
    /// test (the estimate provably misses its mean there, so its z means
    /// nothing); `true`: the row is z-tested like any other, and the flag,
    /// with no other but the batch checks' [`SYMPTOMS`], does not make it
    /// `flagged`.
    pub z_tested: bool,
}

/// Flags that may come with a z-tested row's expected flag: the batch
/// checks (`R`, `VOV`, `FOM`, `tail`), which a heavy-tailed estimate of the
/// cause the expected flag names raises on some runs and not others (the
/// row's z test still guards its value). Any other flag (`sparse`, `near`
/// where it is not expected, `batches`, `enclosed`, `approx`, a
/// reference's `ref:`) is not.
pub const SYMPTOMS: [&str; 4] = ["R", "VOV", "FOM", "tail"];

/// The expected flag of a row of `family`, `case` and `point`, if any.
///
/// This is the complete list; every other row is z-tested, flagged or not.
///
/// - `sparse;near` on the plain local estimate (case without a
///   `near-radius=` label) at the far-field point `plane 1 r=10000` of the
///   `sobolev` family (`near` because the planes lie within a tenth of the
///   distance to the light, the condition under which `--near-radius auto`
///   would split): the reflected light there is carried by chains that wander
///   thousands of plane spacings from the source, and the local estimate
///   only scores collisions that land near the point, which essentially
///   never happens in any affordable run; the estimate is 95-100 % low
///   with a small, steady error bar, so its z is meaningless, and `sparse`
///   is the check that exists to say so. The same point with
///   `near-radius=auto` is z-tested.
/// - `near` on the plain local estimate at `plane 1 r=100` of the `sobolev`
///   family, z-tested: the planes lie 100 times closer than the light, so
///   `near` fires there by geometry, whatever the run; the estimate's heavy
///   tail (chains that cross 100 plane spacings) raises the batch checks on
///   some runs (`R;VOV;tail;near`).
/// - `sparse` on the split (`near-radius=auto`) at `plane 1 r=100` of the
///   `sobolev` family, z-tested: some of the near part's paths come within
///   reach of the light's core, but fewer than 10 enter it, so the part of
///   the light fetched there rests on few samples and the check says so (on
///   every case of the full matrix, and in 20 runs of 65,536 chains at
///   `rho1 rho2 = 0.9` at 38 of their 40 points at r = 100 and 70.7, whose
///   estimates agreed with the exact value: mean z^2 0.83). README, "The far field between highly reflecting
///   surfaces": at r = 100 m no setting gives a precise, unflagged estimate
///   in seconds.
pub fn expected_flag(family: &str, case: &str, point: &str) -> Option<ExpectedFlag> {
    let plain = !case.contains("near-radius=");
    let auto = case.ends_with("near-radius=auto");
    match family {
        "sobolev" if plain && point == "plane 1 r=10000" => Some(ExpectedFlag {
            flag: "sparse;near",
            reason: "far field of the plain local estimate: the collisions that carry \
                     the mean never land near the point (`sparse`), and the planes lie \
                     far closer than a tenth of the distance to the light, where the \
                     plain estimate is not to be trusted (`near`)",
            z_tested: false,
        }),
        "sobolev" if plain && point == "plane 1 r=100" => Some(ExpectedFlag {
            flag: "near",
            reason: "the plain local estimate with the planes 100 times closer than \
                     the light, where it is not to be trusted (`near`, by geometry)",
            z_tested: true,
        }),
        "sobolev" if auto && point == "plane 1 r=100" => Some(ExpectedFlag {
            flag: "sparse",
            reason: "the near part's paths reach the light's core but rarely enter it \
                     at r = 100 m: the light fetched there rests on few samples",
            z_tested: true,
        }),
        _ => None,
    }
}

/// Why the plain local estimate fails at a point of `family` that has a
/// remedy row (module doc, "Known failures and their remedy").
fn known_failure(family: &str) -> &'static str {
    match family {
        "near-wall" => {
            "the plain local estimate misses the light of a wall in view at 1e-6 m \
             (singular kernel h cos / d^4: no collision lands that close)"
        }
        _ => {
            "the plain local estimate misses the far field (the collisions that \
             carry the mean never land near the point)"
        }
    }
}

/// Mark `explained` every `FAIL` row of the plain local estimate (a run
/// that ran, with finite numbers: a failed z test, not an error or a NaN)
/// that carries `near` itself (not its reference) and has no z-tested
/// expected flag, whose remedy row passes: the same family and
/// point in a case that extends the row's case label by a `near-radius=`
/// label, with verdict `pass` (a flagged or failed remedy explains nothing).
pub(super) fn explain(rows: &mut [StressRow]) {
    let remedies: Vec<(String, String, String, Verdict, Option<f64>)> = rows
        .iter()
        .filter(|r| r.case.contains("near-radius="))
        .map(|r| {
            (
                r.family.clone(),
                r.case.clone(),
                r.point.clone(),
                r.verdict,
                r.z,
            )
        })
        .collect();
    for r in rows.iter_mut() {
        let finite = [r.estimate, r.std_error, r.reference_std_error]
            .into_iter()
            .chain(r.reference)
            .chain(r.z)
            .all(f64::is_finite);
        // The estimate's own flags: those before the reference's (`ref:`).
        let own_near = r
            .flag
            .split(';')
            .take_while(|f| !f.starts_with("ref:"))
            .any(|f| f == "near");
        // A row whose expected flag keeps it z-tested is meant to be right:
        // its failure is a failure, whatever its remedy does.
        if r.verdict != Verdict::Fail
            || r.case.contains("near-radius=")
            || r.batches == 0
            || !finite
            || !own_near
            || r.expected.is_some_and(|e| e.z_tested)
        {
            continue;
        }
        let fixed = remedies.iter().find(|m| {
            m.0 == r.family
                && m.2 == r.point
                && m.1.starts_with(&format!("{} near-radius=", r.case))
                && m.3 == Verdict::Pass
        });
        if let Some(m) = fixed {
            r.verdict = Verdict::Explained;
            r.note = format!(
                "{}: case `{}` passes there (|z| = {:.2}); {}",
                known_failure(&r.family),
                m.1,
                m.4.map_or(f64::NAN, f64::abs),
                r.note
            );
        }
    }
}

/// Whether row `r` carries exactly its expected flag where that excuses
/// it from the z test.
fn excused(r: &StressRow) -> bool {
    r.expected.is_some_and(|e| !e.z_tested && r.flag == e.flag)
}

/// Whether z-tested row `r` carries its expected flag, with no other flag
/// but the batch checks' ([`SYMPTOMS`]).
fn carries_expected(r: &StressRow) -> bool {
    r.expected.is_some_and(|e| {
        let flags: Vec<&str> = r.flag.split(';').collect();
        let want: Vec<&str> = e.flag.split(';').collect();
        e.z_tested
            && want.iter().all(|w| flags.contains(w))
            && flags
                .iter()
                .all(|f| want.contains(f) || SYMPTOMS.contains(f))
    })
}

/// Judge every row (module doc, "Verdicts"): finiteness; a failed check of
/// the row's own stays `FAIL`; a row carrying exactly an expected flag that
/// excuses the z test is `expected-flag`; every other row is z-tested
/// against the Sidak bound over the `m` z-tested rows: beyond it `FAIL`
/// whatever the flags, within it `pass` when unflagged, `expected-flag`
/// with its z-tested expected flag (and only the batch checks' besides),
/// and `flagged` otherwise.
pub(super) fn judge(rows: &mut [StressRow], alpha: f64) {
    let m = rows.iter().filter(|r| r.batches > 0 && !excused(r)).count();
    for r in rows.iter_mut() {
        if r.verdict == Verdict::Fail && r.batches == 0 {
            continue; // an error or a panic, already explained
        }
        let mut bad: Vec<&str> = Vec::new();
        for (name, v) in [
            ("estimate", Some(r.estimate)),
            ("std_error", Some(r.std_error)),
            ("exact", r.exact),
            ("reference", r.reference),
            ("reference std_error", Some(r.reference_std_error)),
            ("z", r.z),
        ] {
            if v.is_some_and(|x| !x.is_finite()) {
                bad.push(name);
            }
        }
        r.bound = sidak_bound(alpha, m, Some(r.batches.max(2)));
        let note = |r: &StressRow, s: String| {
            if r.note.is_empty() {
                s
            } else {
                format!("{s}; {}", r.note)
            }
        };
        // What became of the expected flag, for the notes.
        let expected = match r.expected {
            Some(e) if !excused(r) && !carries_expected(r) => format!(
                " (expected flag `{}` {}, so the row is z-tested)",
                e.flag,
                if r.flag == "ok" {
                    "absent"
                } else if e.z_tested {
                    "absent or with flags other than the batch checks'"
                } else {
                    "not alone"
                }
            ),
            _ => String::new(),
        };
        if !bad.is_empty() {
            r.verdict = Verdict::Fail;
            r.note = note(r, format!("not finite: {}", bad.join(", ")));
        } else if r.verdict == Verdict::Fail {
            // Already failed by a check of its own (the note says which).
        } else if let (true, Some(e)) = (excused(r), r.expected) {
            r.verdict = Verdict::ExpectedFlag;
            let z = r.z.map_or(String::new(), |z| {
                format!("; |z| = {:.3e}, not tested", z.abs())
            });
            r.note = note(r, format!("expected flag `{}`: {}{z}", e.flag, e.reason));
        } else {
            match r.z {
                None => {
                    r.verdict = Verdict::Fail;
                    r.note = note(r, "no z score: nothing to test".into());
                }
                Some(z) if zcheck::within(z, r.bound) => {
                    if r.flag == "ok" {
                        r.verdict = Verdict::Pass;
                        if !expected.is_empty() {
                            r.note = note(r, format!("z within the bound{expected}"));
                        }
                    } else if let (true, Some(e)) = (carries_expected(r), r.expected) {
                        r.verdict = Verdict::ExpectedFlag;
                        r.note = note(
                            r,
                            format!(
                                "expected flag `{}`: {}; |z| = {:.2} within the bound {:.2}",
                                e.flag,
                                e.reason,
                                z.abs(),
                                r.bound
                            ),
                        );
                    } else {
                        r.verdict = Verdict::Flagged;
                        r.note = note(
                            r,
                            format!(
                                "diagnostics: {} (|z| = {:.2} within the bound {:.2}){expected}",
                                r.flag,
                                z.abs(),
                                r.bound
                            ),
                        );
                    }
                }
                Some(z) => {
                    r.verdict = Verdict::Fail;
                    let flags = if r.flag == "ok" {
                        "not flagged".to_string()
                    } else {
                        format!("flags: {}", r.flag)
                    };
                    r.note = note(
                        r,
                        format!(
                            "|z| = {:.2} beyond the Sidak bound {:.2}, {flags}{expected}",
                            z.abs(),
                            r.bound
                        ),
                    );
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cases::stress::families::NEAR_WALL_LABEL;
    use crate::cases::stress::row::summary_csv;

    /// A finished row of `family` / `case` / `point` with z score `z`
    /// (estimate 1 + z/100 against the exact 1, error 0.01) and flag `flag`.
    fn row(family: &str, case: &str, point: &str, z: f64, flag: &str) -> StressRow {
        StressRow {
            family: family.into(),
            case: case.into(),
            point: point.into(),
            estimate: 1.0 + 0.01 * z,
            std_error: 0.01,
            direct: 0.5,
            exact: Some(1.0),
            reference_kind: "exact".into(),
            reference: Some(1.0),
            reference_std_error: 0.0,
            rel_err: Some(0.01 * z),
            z: Some(z),
            time: 1.0,
            chains: 65536,
            batches: 128,
            batch_chains: 512,
            flag: flag.into(),
            checks: (None, None),
            expected: expected_flag(family, case, point),
            bound: 0.0,
            verdict: Verdict::Pass,
            note: String::new(),
        }
    }

    fn verdicts(rows: &[StressRow]) -> Vec<Verdict> {
        rows.iter().map(|r| r.verdict).collect()
    }

    /// The checks of 40 batch means, 39 at 10 +- 1 and one at `v`, alone
    /// in their run.
    fn outlier_checks(v: f64) -> crate::tally::Diagnostics {
        let mut w = crate::tally::Welford::new();
        for b in 0..40 {
            w.push(match b {
                17 => v,
                b if b % 2 == 0 => 11.0,
                _ => 9.0,
            });
        }
        crate::tally::Diagnostics::of(&w, 0.0, None, 1)
    }

    /// A tail flagged by its own run's bounds is held over the matrix
    /// before the rows are judged: among 1000 rows it is no false alarm,
    /// the estimate's and the reference's alike, while a tail beyond every
    /// bound stays flagged; a row without checks keeps its flag.
    #[test]
    fn flags_are_held_over_the_whole_matrix() {
        // The smallest outlier flagged alone (the tail bound for 40 batches
        // lies well below the largest deviation they can reach, 6.2).
        let v = (0..4000)
            .map(|i| 10.0 + 0.01 * f64::from(i))
            .find(|&v| outlier_checks(v).flag() == "tail")
            .expect("a flagged outlier");
        let (d, huge) = (outlier_checks(v), outlier_checks(1e6));
        assert!(d.among(2000).flag() == "ok" && huge.among(2000).flag().contains("tail"));
        let mut rows: Vec<StressRow> = (0..1000)
            .map(|k| {
                let mut r = row(
                    "sobolev",
                    "rho1rho2=0.9 h1=0.5",
                    &format!("p{k}"),
                    0.0,
                    "ok",
                );
                r.checks = (Some(outlier_checks(10.0)), None);
                r
            })
            .collect();
        rows[0].checks = (Some(d), None);
        rows[1].checks = (Some(outlier_checks(10.0)), Some(d));
        rows[2].checks = (Some(huge), None);
        rows[3].checks = (None, None);
        rows[3].flag = "kept".into();
        for r in &mut rows {
            r.flag = super::super::row::joined_flag(r.checks);
        }
        rows[3].flag = "kept".into();
        assert_eq!(rows[0].flag, "tail");
        assert_eq!(rows[1].flag, "ref:tail");
        super::super::row::reflag(&mut rows);
        assert_eq!(rows[0].flag, "ok");
        assert_eq!(rows[1].flag, "ok");
        assert!(rows[2].flag.contains("tail"), "{}", rows[2].flag);
        assert_eq!(rows[3].flag, "kept");
        assert_eq!(rows[0].checks.0.unwrap().family, 1000);
    }

    #[test]
    fn only_the_expected_flag_excuses_a_row_from_the_z_test() {
        let far = "plane 1 r=10000";
        let mut rows = vec![
            // 0: clean and within the bound.
            row("near-source", "c", "a", 0.5, "ok"),
            // 1: an arbitrary flag does not excuse a large z (the old gate
            // called this row `flagged` and did not test it).
            row("near-source", "c", "b", 50.0, "VOV"),
            row("near-wall", "c", "c", -1e6, "sparse"),
            // 3: an unexpected flag with z within the bound.
            row("near-source", "c", "d", 0.5, "tail"),
            // 4: the expected flag alone excuses any z.
            row("sobolev", "rho1rho2=0.99 h1=0.5", far, -4e6, "sparse;near"),
            // 5: the expected flag with a flag that is not a statistical
            // symptom does not.
            row(
                "sobolev",
                "rho1rho2=0.9 h1=0.5",
                far,
                -4e6,
                "batches;sparse;near",
            ),
            // 6: the expected flag absent: tested like any row.
            row("sobolev", "rho1rho2=0.9 h1=0.01", far, -4e6, "ok"),
            row("sobolev", "rho1rho2=0.9 h1=0.01", far, 0.3, "ok"),
            // 8: `sparse` is expected on the plain estimate only.
            row(
                "sobolev",
                "rho1rho2=0.9 h1=0.5 near-radius=auto",
                far,
                30.0,
                "sparse;near",
            ),
            // 9: not finite.
            row("near-source", "c", "e", f64::NAN, "ok"),
            row("near-source", "c", "f", f64::INFINITY, "tail"),
            // 11: an excusing expected flag with the batch checks' flags
            // does not excuse; 12: nor does part of it.
            row(
                "sobolev",
                "rho1rho2=0.99 h1=0.01",
                far,
                -4e6,
                "VOV;tail;sparse;near",
            ),
            row("sobolev", "rho1rho2=0.99 h1=0.001", far, -4e6, "VOV;near"),
            // 13: `near` is expected at r = 100, z-tested (with the batch
            // checks' flags); 14: `sparse` on the split there, z-tested;
            // 15: neither elsewhere.
            row(
                "sobolev",
                "rho1rho2=0.9 h1=0.5",
                "plane 1 r=100",
                -1.7,
                "R;VOV;tail;near",
            ),
            row(
                "sobolev",
                "rho1rho2=0.9 h1=0.5 near-radius=auto",
                "plane 1 r=100",
                1.2,
                "sparse",
            ),
            row("sobolev", "rho1rho2=0.9 h1=0.5", "plane 1 r=0", 0.5, "near"),
            // 16: a z-tested expected flag does not excuse a large z; 17:
            // `sparse` is not a symptom that may come with `near`.
            row(
                "sobolev",
                "rho1rho2=0.99 h1=0.5",
                "plane 1 r=100",
                -4e6,
                "near",
            ),
            row(
                "sobolev",
                "rho1rho2=0.99 h1=0.01",
                "plane 1 r=100",
                -1.0,
                "sparse;near",
            ),
        ];
        judge(&mut rows, 0.01);
        use Verdict::*;
        assert_eq!(
            verdicts(&rows),
            [
                Pass,
                Fail,
                Fail,
                Flagged,
                ExpectedFlag,
                Fail,
                Fail,
                Pass,
                Fail,
                Fail,
                Fail,
                Fail,
                Fail,
                ExpectedFlag,
                ExpectedFlag,
                Flagged,
                Fail,
                Flagged
            ]
        );
        // One excused row: the others are the Sidak family.
        let bound = sidak_bound(0.01, rows.len() - 1, Some(128));
        assert!(rows.iter().all(|r| r.bound == bound), "{bound}");
        assert!(rows[1].note.contains("flags: VOV"), "{}", rows[1].note);
        assert!(rows[5].note.contains("not alone"), "{}", rows[5].note);
        assert!(
            rows[14].note.contains("within the bound"),
            "{}",
            rows[14].note
        );
        assert!(rows[6].note.contains("absent"), "{}", rows[6].note);
    }

    #[test]
    fn a_zero_error_counts_only_when_exact() {
        let mut rows = vec![
            row("near-source", "c", "a", 0.0, "ok"),
            row("near-source", "c", "b", 0.0, "ok"),
        ];
        for r in &mut rows {
            r.std_error = 0.0;
        }
        rows[0].z = Some(zcheck::z_of_difference(0.0, 0.0));
        rows[1].z = Some(zcheck::z_of_difference(1e-15, 0.0));
        judge(&mut rows, 0.01);
        assert_eq!(verdicts(&rows), [Verdict::Pass, Verdict::Fail]);
    }

    #[test]
    fn only_a_passing_remedy_explains_a_failure() {
        let wall = "box room rho=0.8";
        let fixed = format!("{wall} {NEAR_WALL_LABEL}");
        let mut rows = vec![
            row("near-wall", wall, "a", -100.0, "VOV;near"),
            row("near-wall", &fixed, "a", 0.5, "ok"),
            row("near-wall", wall, "b", -100.0, "near"),
            row("near-wall", &fixed, "b", 0.5, "VOV"),
            row("near-wall", wall, "c", -100.0, "near"),
            row("near-wall", &fixed, "c", 80.0, "ok"),
            // No remedy row.
            row("near-wall", wall, "d", -100.0, "near"),
            // A remedy of another case does not count.
            row("near-wall", "box room rho=0.9", "a", -100.0, "near"),
            // A NaN is a bug, not the known failure, whatever the remedy.
            row("near-wall", wall, "e", f64::NAN, "near"),
            row("near-wall", &fixed, "e", 0.5, "ok"),
            // A failure without `near`, the plain estimate's warning, is
            // an unflagged wrong answer, whatever the remedy; so is one
            // whose `near` is its reference's.
            row("near-wall", wall, "f", -100.0, "ok"),
            row("near-wall", &fixed, "f", 0.5, "ok"),
            row("near-wall", wall, "g", -100.0, "ref:R;near"),
            row("near-wall", &fixed, "g", 0.5, "ok"),
            // A plain row whose `near` is expected and z-tested (r = 100)
            // is meant to be right: a passing split explains nothing.
            row(
                "sobolev",
                "rho1rho2=0.9 h1=0.5",
                "plane 1 r=100",
                -50.0,
                "near",
            ),
            row(
                "sobolev",
                "rho1rho2=0.9 h1=0.5 near-radius=auto",
                "plane 1 r=100",
                0.5,
                "ok",
            ),
        ];
        judge(&mut rows, 0.01);
        explain(&mut rows);
        use Verdict::*;
        assert_eq!(
            verdicts(&rows),
            [
                Explained, Pass, Fail, Flagged, Fail, Fail, Fail, Fail, Fail, Pass, Fail, Pass,
                Fail, Pass, Fail, Pass
            ]
        );
        let csv = String::from_utf8(summary_csv(&rows)).unwrap();
        let mut lines = csv.lines();
        assert!(
            lines
                .next()
                .unwrap()
                .starts_with("family,rows,pass,expected-flag,flagged,explained,FAIL,")
        );
        assert!(
            lines.next().unwrap().starts_with("near-wall,14,4,0,1,1,8,"),
            "{csv}"
        );
    }
}
