//! The tool path to compensate: TCP poses in the robot model's world frame, in order, with the
//! arc length along the TCP positions, the feed of the move that ends at each point and the time
//! at which the point is reached at those feeds.

use crate::error::PathError;
use deflex_model::Pose;
use nalgebra::Vector3;

/// Largest number of points of a path (a compensated point takes a few hundred bytes).
pub const MAX_PATH_POINTS: usize = 1_000_000;

/// Largest |coordinate| of a TCP position (m).
pub const MAX_COORDINATE_M: f64 = 100.0;

/// Largest feed rate (m/s).
pub const MAX_FEED_M_S: f64 = 10.0;

/// One point of a path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathPoint {
    /// Desired TCP pose in the world frame (m).
    pub pose: Pose,
    /// Arc length along the TCP positions from the first point (m).
    pub arc_length_m: f64,
    /// Time at which the point is reached (s), at the feeds (rapids at the rapid feed).
    pub time_s: f64,
    /// Feed of the move ending here (m/s); `None`: a rapid move (and the first point).
    pub feed_m_s: Option<f64>,
}

/// A checked tool path.
#[derive(Clone, Debug, PartialEq)]
pub struct TcpPath {
    name: String,
    points: Vec<PathPoint>,
}

impl TcpPath {
    /// A path from poses (world, m) and feeds (m/s, `None` = rapid); rapid moves are timed at
    /// `rapid_feed_m_s`. Checks the size, every position, rotation and feed.
    pub fn new(
        name: &str,
        poses: impl IntoIterator<Item = (Pose, Option<f64>)>,
        rapid_feed_m_s: f64,
    ) -> Result<TcpPath, PathError> {
        let name = name.to_string();
        let mut points: Vec<PathPoint> = Vec::new();
        for (index, (pose, feed)) in poses.into_iter().enumerate() {
            if index >= MAX_PATH_POINTS {
                return Err(PathError::TooManyPoints {
                    name,
                    max: MAX_PATH_POINTS,
                });
            }
            let t = pose.translation.vector;
            for (field, value) in [("x_m", t.x), ("y_m", t.y), ("z_m", t.z)] {
                if !(value.is_finite() && value.abs() <= MAX_COORDINATE_M) {
                    return Err(PathError::BadPosition {
                        name,
                        index,
                        field,
                        value,
                        limit: MAX_COORDINATE_M,
                    });
                }
            }
            let m = pose.rotation.matrix();
            let deviation = (m.transpose() * m - nalgebra::Matrix3::identity()).amax();
            if !(deviation < 1e-9 && (m.determinant() - 1.0).abs() < 1e-9) {
                return Err(PathError::BadRotation { name, index });
            }
            if let Some(f) = feed
                && !(f.is_finite() && f > 0.0 && f <= MAX_FEED_M_S)
            {
                return Err(PathError::BadFeed {
                    name,
                    index,
                    value: f,
                });
            }
            let (arc_length_m, time_s) = match points.last() {
                Some(previous) => {
                    let step = (t - previous.pose.translation.vector).norm();
                    let speed = feed.unwrap_or(rapid_feed_m_s);
                    (previous.arc_length_m + step, previous.time_s + step / speed)
                }
                None => (0.0, 0.0),
            };
            points.push(PathPoint {
                pose,
                arc_length_m,
                time_s,
                feed_m_s: if index == 0 { None } else { feed },
            });
        }
        if points.len() < 2 {
            return Err(PathError::TooFewPoints {
                name,
                points: points.len(),
            });
        }
        if !(rapid_feed_m_s.is_finite() && rapid_feed_m_s > 0.0 && rapid_feed_m_s <= MAX_FEED_M_S) {
            return Err(PathError::BadFeed {
                name,
                index: 0,
                value: rapid_feed_m_s,
            });
        }
        Ok(TcpPath { name, points })
    }

    /// The path's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The points.
    pub fn points(&self) -> &[PathPoint] {
        &self.points
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Never true (a path has at least two points); for clippy's `len` convention.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Length along the TCP positions (m).
    pub fn length_m(&self) -> f64 {
        self.points.last().map_or(0.0, |p| p.arc_length_m)
    }

    /// Time to follow the path (s).
    pub fn duration_s(&self) -> f64 {
        self.points.last().map_or(0.0, |p| p.time_s)
    }

    /// Unit direction of travel at point `index` (world): from the previous point, or towards
    /// the next one at the first point; zero where the TCP does not move.
    pub fn travel_direction(&self, index: usize) -> Vector3<f64> {
        let (a, b) = if index == 0 {
            (0, 1.min(self.points.len() - 1))
        } else {
            (index - 1, index)
        };
        let d = self.points[b].pose.translation.vector - self.points[a].pose.translation.vector;
        let n = d.norm();
        if n > 1e-12 { d / n } else { Vector3::zeros() }
    }

    /// The segment `(i, f)` holding arc length `s` (clamped to the path): the point lies between
    /// points `i` and `i + 1` at fraction `f ∈ [0, 1]`. Binary search, no allocation.
    pub fn locate(&self, s: f64) -> (usize, f64) {
        let last = self.points.len() - 1;
        if s.is_nan() || s <= 0.0 {
            return (0, 0.0);
        }
        if s >= self.points[last].arc_length_m {
            return (last - 1, 1.0);
        }
        let i = self.points.partition_point(|p| p.arc_length_m <= s) - 1;
        let i = i.min(last - 1);
        let span = self.points[i + 1].arc_length_m - self.points[i].arc_length_m;
        let f = if span > 0.0 {
            (s - self.points[i].arc_length_m) / span
        } else {
            0.0
        };
        (i, f.clamp(0.0, 1.0))
    }
}
