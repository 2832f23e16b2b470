//! Regions of space (`"all"`, box, ball, half space) used by `[[fluid.init]]`,
//! `[[solid.constraints]]` and `[[solid.init]]`, and their own consistency.

use serde::{Deserialize, Serialize};

use super::error::quote_list;

/// A region of space.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Region {
    /// The whole domain (`region = "all"`).
    All,
    /// Axis-aligned box.
    Box {
        /// Lower corner.
        lower: Vec<f64>,
        /// Upper corner.
        upper: Vec<f64>,
    },
    /// Ball (disc in 2-D, interval in 1-D).
    Ball {
        /// Centre.
        center: Vec<f64>,
        /// Radius \[m\].
        radius: f64,
    },
    /// Half space: the side opposite to `normal` (the normal points out of it).
    HalfSpace {
        /// A point on the plane.
        point: Vec<f64>,
        /// Outward normal (need not be unit).
        normal: Vec<f64>,
    },
}

impl Region {
    /// Whether `x` lies in the region (boundaries included).
    pub fn contains(&self, x: &[f64]) -> bool {
        match self {
            Region::All => true,
            Region::Box { lower, upper } => x
                .iter()
                .zip(lower.iter().zip(upper))
                .all(|(xi, (lo, hi))| *lo <= *xi && *xi <= *hi),
            Region::Ball { center, radius } => {
                let d2: f64 = x.iter().zip(center).map(|(a, b)| (a - b) * (a - b)).sum();
                d2 <= radius * radius
            }
            Region::HalfSpace { point, normal } => {
                let s: f64 = x
                    .iter()
                    .zip(point.iter().zip(normal))
                    .map(|(xi, (pi, ni))| (xi - pi) * ni)
                    .sum();
                s <= 0.0
            }
        }
    }

    pub(super) fn vectors(&self) -> Vec<(&'static str, &Vec<f64>)> {
        match self {
            Region::All => vec![],
            Region::Box { lower, upper } => vec![("box.lower", lower), ("box.upper", upper)],
            Region::Ball { center, .. } => vec![("ball.center", center)],
            Region::HalfSpace { point, normal } => {
                vec![("half_space.point", point), ("half_space.normal", normal)]
            }
        }
    }
}

impl Region {
    /// Whether the region meets the box `[lower, upper]` (touching counts).
    pub(super) fn meets_box(&self, lower: &[f64], upper: &[f64]) -> bool {
        let corners = lower.iter().zip(upper);
        match self {
            Region::All => true,
            Region::Box {
                lower: lo,
                upper: hi,
            } => corners
                .zip(lo.iter().zip(hi))
                .all(|((d_lo, d_hi), (lo, hi))| lo <= d_hi && hi >= d_lo),
            Region::Ball { center, radius } => {
                let d2: f64 = corners
                    .zip(center)
                    .map(|((d_lo, d_hi), c)| {
                        let gap = (d_lo - c).max(c - d_hi).max(0.0);
                        gap * gap
                    })
                    .sum();
                d2 <= radius * radius
            }
            // The box corner deepest on the inner side (normal points out of the half space).
            Region::HalfSpace { point, normal } => {
                let s: f64 = corners
                    .zip(point.iter().zip(normal))
                    .map(|((d_lo, d_hi), (p, n))| (if *n > 0.0 { d_lo } else { d_hi } - p) * n)
                    .sum();
                s <= 0.0
            }
        }
    }
}

/// A region's own consistency: a ball's radius > 0, a box's lower <= upper, a half space's
/// normal not zero. Returns `(key path, expected, found)`.
pub(super) fn check_region(base: &str, region: &Region) -> Result<(), (String, String, String)> {
    match region {
        Region::All => Ok(()),
        Region::Ball { radius, .. } if !(radius.is_finite() && *radius > 0.0) => Err((
            format!("{base}.ball.radius"),
            "a finite radius > 0".into(),
            radius.to_string(),
        )),
        Region::Box { lower, upper } if lower.iter().zip(upper).any(|(lo, hi)| lo > hi) => Err((
            format!("{base}.box"),
            "lower <= upper on every axis".into(),
            format!(
                "lower {} and upper {}",
                quote_list(lower),
                quote_list(upper)
            ),
        )),
        Region::HalfSpace { normal, .. } if normal.iter().all(|n| *n == 0.0) => Err((
            format!("{base}.half_space.normal"),
            "a normal that is not zero".into(),
            quote_list(normal),
        )),
        _ => Ok(()),
    }
}
