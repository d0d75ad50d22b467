//! The Pareto front of configurations that trade time for error.

/// For each point `(time, error)`, whether no other point is at least as good in both and
/// better in one (both minimized). Points with a non-finite coordinate are never on the front
/// and dominate nothing.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    let ok = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
    points
        .iter()
        .map(|p| {
            ok(p)
                && !points
                    .iter()
                    .any(|q| ok(q) && q.0 <= p.0 && q.1 <= p.1 && (q.0 < p.0 || q.1 < p.1))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dominated_points_are_off_the_front() {
        let pts = [
            (1.0, 5.0),
            (2.0, 3.0),
            (3.0, 3.5),
            (4.0, 1.0),
            (2.0, 3.0),
            (f64::NAN, 0.0),
        ];
        assert_eq!(pareto_front(&pts), [true, true, false, true, true, false]);
        assert!(pareto_front(&[]).is_empty());
    }
}
