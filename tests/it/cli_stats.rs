//! `mbfmu simulate --stats`: the integrator's statistics and the wall time on stderr at the
//! end of the run. The counts printed are the engine's (`Simulator::stats` of the same run
//! made in-process), they hold together (every attempt is accepted or rejected, every
//! communication step takes at least one accepted step, ...), and a failed run prints the
//! work up to the failure.

use std::collections::BTreeMap;

use crate::common::{mbfmu, model};
use mbfmu::dae::{SimOptions, Simulator};

/// The counts of the report, by label: (total, per communication step).
struct Report {
    communication_steps: usize,
    failed: bool,
    counts: BTreeMap<String, (usize, f64)>,
    wall: f64,
}

impl Report {
    fn parse(stderr: &str) -> Report {
        let head =
            stderr.lines().find(|l| l.starts_with("integrator statistics: ")).unwrap_or_else(|| panic!("{stderr}"));
        let communication_steps = head["integrator statistics: ".len()..].split(' ').next().unwrap().parse().unwrap();
        let mut counts = BTreeMap::new();
        for line in stderr.lines().filter(|l| l.starts_with("  ") && l.contains(':')) {
            let (label, rest) = line.trim().split_once(':').unwrap();
            let mut f = rest.split_whitespace();
            let total = f.next().unwrap().parse().unwrap_or_else(|e| panic!("{line}: {e}"));
            let per = f.next().unwrap().parse().unwrap_or(f64::NAN);
            counts.insert(label.to_string(), (total, per));
        }
        let wall = stderr.lines().find_map(|l| l.strip_prefix("wall time: ")).unwrap_or_else(|| panic!("{stderr}"));
        Report {
            communication_steps,
            failed: head.ends_with("(the last failed)"),
            counts,
            wall: wall.split(' ').next().unwrap().parse().unwrap(),
        }
    }

    fn total(&self, label: &str) -> usize {
        self.counts.get(label).unwrap_or_else(|| panic!("no '{label}' in {:?}", self.counts.keys())).0
    }
}

const LABELS: [&str; 10] = [
    "steps attempted",
    "accepted steps",
    "rejected steps",
    "Newton iterations",
    "Jacobian evaluations",
    "exact ones",
    "factorizations",
    "by the general LU",
    "symbolic analyses",
    "rhs evaluations",
];

#[test]
fn simulate_stats_prints_consistent_counts_equal_to_the_engines() {
    // The double pendulum (chaotic after release, so the step size varies) over 1 s in 20
    // communication steps of 0.05 s.
    let o =
        mbfmu(&["simulate", "models/double_pendulum.xml", "--end", "1", "--step", "0.05", "--tol", "1e-8", "--stats"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let csv = String::from_utf8_lossy(&o.stdout);
    assert_eq!(csv.lines().count(), 1 + 21, "header and 21 rows on stdout, the statistics elsewhere");
    assert!(!csv.contains("integrator statistics"));
    let r = Report::parse(&err);
    assert_eq!(r.communication_steps, 20, "{err}");
    assert!(!r.failed, "{err}");
    assert_eq!(r.counts.len(), LABELS.len(), "{err}");
    for label in LABELS {
        let (total, per) = r.counts[label];
        // The average is the total over the communication steps, printed to 2 decimals.
        assert!((per - total as f64 / 20.0).abs() <= 0.005 + 1e-12, "{label}: {total} / 20 printed {per}");
    }
    let (steps, accepted, rejected) =
        (r.total("steps attempted"), r.total("accepted steps"), r.total("rejected steps"));
    assert_eq!(accepted + rejected, steps, "every attempt is accepted or rejected: {err}");
    assert!(accepted >= r.communication_steps, "each communication step ends on an accepted step: {err}");
    let newton = r.total("Newton iterations");
    assert!(newton >= accepted, "an accepted step took at least one Newton iteration: {err}");
    assert!(r.total("rhs evaluations") >= 3 * newton, "each Newton iteration evaluates f at 3 stages: {err}");
    assert!(r.total("Jacobian evaluations") >= 1 && r.total("factorizations") >= 1, "{err}");
    assert!(r.total("symbolic analyses") >= 1, "{err}");
    assert!(r.total("by the general LU") <= r.total("factorizations"), "{err}");
    assert!(r.total("symbolic analyses") <= 2 * r.total("factorizations"), "two matrices per factorization: {err}");
    assert!(r.wall >= 0.0 && r.wall.is_finite(), "{err}");

    // The same run in-process: the printed counts are the engine's.
    let m = model("double_pendulum.xml");
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-8, ..Default::default() }, 0.0).unwrap();
    for k in 1..=20 {
        sim.advance(k as f64 * 0.05).unwrap();
    }
    let s = sim.stats();
    let want = [
        s.steps,
        s.accepted,
        s.rejected,
        s.newton_iterations,
        s.jacobians,
        s.exact_jacobians,
        s.factorizations,
        s.general_factorizations,
        s.symbolic_analyses,
        s.rhs_evaluations,
    ];
    for (label, want) in LABELS.iter().zip(want) {
        assert_eq!(r.total(label), want, "{label}: {err}");
    }
}

#[test]
fn simulate_without_stats_prints_none_and_a_failed_run_prints_the_work_up_to_the_failure() {
    let o = mbfmu(&["simulate", "models/pendulum.xml", "--end", "0.1"]);
    assert!(o.status.success());
    assert!(o.stderr.is_empty(), "{}", String::from_utf8_lossy(&o.stderr));

    // One attempt cannot cover a 1 s communication step of the pendulum: the step limit,
    // after exactly one attempt, in the one communication step taken.
    let o = mbfmu(&["simulate", "models/pendulum.xml", "--end", "1", "--step", "1", "--max-steps", "1", "--stats"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("step limit reached: 1 integrator steps"), "{err}");
    let r = Report::parse(&err);
    assert!(r.failed && r.communication_steps == 1, "{err}");
    assert_eq!(r.total("steps attempted"), 1, "{err}");
    assert!(r.total("accepted steps") + r.total("rejected steps") <= 1, "{err}");
    // The statistics come before the error line.
    assert!(err.find("integrator statistics").unwrap() < err.find("error:").unwrap(), "{err}");
}

#[test]
fn a_run_that_needs_the_exact_jacobian_counts_it_and_keeps_it() {
    // The four-bar at 1e-6: its Newton iteration soon fails with the within-body
    // approximation of J (a closed loop's reactions couple its links), and the run takes
    // the exact J from then on.
    let o = mbfmu(&["simulate", "models/fourbar.xml", "--end", "0.2", "--step", "0.01", "--tol", "1e-6", "--stats"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let r = Report::parse(&err);
    let (jac, exact) = (r.total("Jacobian evaluations"), r.total("exact ones"));
    assert!(exact > 0, "the run switched to the exact J: {err}");
    assert!(exact < jac, "the first J is the approximation: {err}");

    let m = model("fourbar.xml");
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-6, ..Default::default() }, 0.0).unwrap();
    let mut approximate_after_switch = None;
    for k in 1..=20 {
        sim.advance(k as f64 * 0.01).unwrap();
        let s = sim.stats();
        let approximate = s.jacobians - s.exact_jacobians;
        if let Some(a) = approximate_after_switch {
            assert_eq!(approximate, a, "no approximate J after the switch (communication step {k})");
        } else if s.exact_jacobians > 0 {
            approximate_after_switch = Some(approximate);
        }
    }
    let s = sim.stats();
    assert_eq!((s.jacobians, s.exact_jacobians), (jac, exact), "the printed counts are the engine's");
    assert!(approximate_after_switch.is_some());
}
