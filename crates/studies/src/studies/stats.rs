//! Record-to-record statistics shared by the record-based studies (`stiffness`, `modes`,
//! `restitution`, `gap`, `cost`, `modelform`, `yielding`) and the sweep's case rows
//! (`crate::sweep`: a case's median approach speed).
//!
//! Responses to different ground motions are not samples of one distribution with a
//! meaningful mean (a few strong pulses dominate a mean), so the studies report the median
//! and the 16th and 84th percentiles (the ±1σ points of a normal, hence of a lognormal in
//! log space).
//!
//! Percentile definition (Hyndman & Fan type 7, the default of NumPy and R): for the finite
//! values sorted, x₀ ≤ … ≤ x_{n−1}, and p ∈ [0, 1],
//!
//! ```text
//! h = (n − 1) p,   Q(p) = x_⌊h⌋ + (h − ⌊h⌋) (x_⌊h⌋+1 − x_⌊h⌋)
//! ```
//!
//! so Q(0) is the minimum, Q(1) the maximum and Q(½) the usual median.
//!
//! Convergence slopes: the log–log least-squares slope of y against x over x ≥ x_min,
//! `log10 y = a + s log10 x` ([`loglog_slope`]).

use super::fit_line;
use crate::plot::Series;
use crate::table::f;

/// The p-quantile (p in [0, 1]) of the finite values, type 7 (see the module docs); `None`
/// without finite values or with p outside [0, 1].
pub fn percentile(values: &[f64], p: f64) -> Option<f64> {
    if !(0.0..=1.0).contains(&p) {
        return None;
    }
    let mut x: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if x.is_empty() {
        return None;
    }
    x.sort_by(f64::total_cmp);
    let h = (x.len() - 1) as f64 * p;
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(x.len() - 1);
    Some(x[lo] + (h - lo as f64) * (x[hi] - x[lo]))
}

/// The median of the finite values.
pub fn median(values: &[f64]) -> Option<f64> {
    percentile(values, 0.5)
}

/// Median and 16th/84th percentiles of a set of per-record values, with their count.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spread {
    /// Number of finite values.
    pub n: usize,
    pub median: Option<f64>,
    pub p16: Option<f64>,
    pub p84: Option<f64>,
}

impl Spread {
    /// The spread of the finite values among `values`.
    pub fn of(values: impl IntoIterator<Item = f64>) -> Self {
        let v: Vec<f64> = values.into_iter().filter(|x| x.is_finite()).collect();
        Spread {
            n: v.len(),
            median: median(&v),
            p16: percentile(&v, 0.16),
            p84: percentile(&v, 0.84),
        }
    }

    /// Three table cells: median, 16th and 84th percentile with `decimals` decimals.
    pub fn cells(&self, decimals: usize) -> [String; 3] {
        [
            f(self.median, decimals),
            f(self.p16, decimals),
            f(self.p84, decimals),
        ]
    }

    /// Three table cells in scientific notation.
    pub fn cells_e(&self, digits: usize) -> [String; 3] {
        let e = crate::table::e;
        [
            e(self.median, digits),
            e(self.p16, digits),
            e(self.p84, digits),
        ]
    }

    /// "median (16–84 %: a–b)" for the readings.
    pub fn words(&self, decimals: usize) -> String {
        format!(
            "{} (16–84 %: {}–{})",
            f(self.median, decimals),
            f(self.p16, decimals),
            f(self.p84, decimals)
        )
    }
}

/// Least-squares slope and intercept of log10 y on log10 x over the points with x ≥ x_min
/// and x, y > 0; `None` with fewer than two such points at distinct x.
pub fn loglog_slope(pts: &[(f64, f64)], x_min: f64) -> Option<(f64, f64)> {
    let lp: Vec<(f64, f64)> = pts
        .iter()
        .filter(|(x, y)| *x >= x_min && *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x.log10(), y.log10()))
        .collect();
    fit_line(&lp)
}

/// A median line with its 16–84 % band for a figure: the median as a solid named series
/// (so its legend swatch matches), the two percentiles as thin dashed unnamed lines of the
/// same colour (explained in the caption). Points with no median are skipped.
pub fn median_band(name: &str, color: usize, pts: &[(f64, Spread)]) -> Vec<Series> {
    let take = |g: fn(&Spread) -> Option<f64>| -> Vec<(f64, f64)> {
        pts.iter()
            .filter_map(|(x, s)| g(s).map(|y| (*x, y)))
            .collect()
    };
    vec![
        Series::line(name, take(|s| s.median), color),
        Series::line("", take(|s| s.p16), color).dashed().width(1),
        Series::line("", take(|s| s.p84), color).dashed().width(1),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_by_hand() {
        // Sorted: 1, 2, 4, 8, 16 (n = 5, h = 4p).
        let v = [8.0, 1.0, 16.0, 2.0, 4.0];
        assert_eq!(percentile(&v, 0.0), Some(1.0));
        assert_eq!(percentile(&v, 1.0), Some(16.0));
        assert_eq!(median(&v), Some(4.0));
        // p = 0.16: h = 0.64 → 1 + 0.64·(2 − 1) = 1.64.
        assert!((percentile(&v, 0.16).unwrap() - 1.64).abs() < 4.0 * f64::EPSILON);
        // p = 0.84: h = 3.36 → 8 + 0.36·(16 − 8) = 10.88.
        assert!((percentile(&v, 0.84).unwrap() - 10.88).abs() < 16.0 * f64::EPSILON);
        // Even count: median halfway between the middle two.
        assert_eq!(median(&[3.0, 1.0, 2.0, 10.0]), Some(2.5));
        // One value: every percentile is that value.
        assert_eq!(percentile(&[7.0], 0.84), Some(7.0));
    }

    #[test]
    fn percentiles_skip_non_finite_and_refuse_nonsense() {
        let v = [f64::NAN, 3.0, f64::INFINITY, 1.0];
        assert_eq!(median(&v), Some(2.0));
        assert_eq!(median(&[]), None);
        assert_eq!(median(&[f64::NAN]), None);
        assert_eq!(percentile(&[1.0, 2.0], 1.5), None);
        assert_eq!(percentile(&[1.0, 2.0], -0.1), None);
    }

    #[test]
    fn spread_counts_finite_values() {
        let s = Spread::of([2.0, f64::NAN, 1.0, 3.0]);
        assert_eq!(s.n, 3);
        assert_eq!(s.median, Some(2.0));
        // h = 2·0.16 = 0.32 → 1.32; h = 2·0.84 = 1.68 → 2.68.
        assert!((s.p16.unwrap() - 1.32).abs() < 4.0 * f64::EPSILON);
        assert!((s.p84.unwrap() - 2.68).abs() < 4.0 * f64::EPSILON);
        assert_eq!(
            s.cells(2),
            ["2.00".to_string(), "1.32".into(), "2.68".into()]
        );
        let none = Spread::of([]);
        assert_eq!((none.n, none.median), (0, None));
        assert_eq!(none.cells(1), ["–".to_string(), "–".into(), "–".into()]);
    }

    #[test]
    fn loglog_slope_recovers_a_power_law_over_the_fit_range() {
        // e = 3·k^−0.5 for k ≥ 1e11; the points below the fit range follow another law
        // and must be ignored; a zero error is not a point of a log–log fit.
        let mut pts: Vec<(f64, f64)> = [1e11, 1e12, 1e13]
            .iter()
            .map(|&k: &f64| (k, 3.0 * k.powf(-0.5)))
            .collect();
        pts.push((1e9, 1.0));
        pts.push((1e10, 0.0));
        let (s, a) = loglog_slope(&pts, 1e11).unwrap();
        assert!((s + 0.5).abs() < 1e-12, "{s}");
        assert!((a - 3f64.log10()).abs() < 1e-11, "{a}");
        // By hand: points (11, −1), (12, −3): slope −2.
        let (s, _) = loglog_slope(&[(1e11, 0.1), (1e12, 0.001)], 0.0).unwrap();
        assert!((s + 2.0).abs() < 1e-12);
        // One point in range: no slope.
        assert_eq!(loglog_slope(&pts, 1e13), None);
    }

    #[test]
    fn median_band_names_only_the_median() {
        let pts = [
            (1.0, Spread::of([1.0, 2.0, 3.0])),
            (2.0, Spread::of([f64::NAN])),
        ];
        let s = median_band("m", 3, &pts);
        assert_eq!(s.len(), 3);
        assert_eq!(s[0].name, "m");
        assert!(!s[0].dashed && s[1].dashed && s[2].dashed);
        assert!(s[1].name.is_empty() && s[2].name.is_empty());
        assert_eq!(s[0].points, vec![(1.0, 2.0)]);
        assert_eq!(s[1].points.len(), 1);
    }
}
