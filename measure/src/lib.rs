//! # oslf-measure: what each setting costs and buys
//!
//! Users of offset surface light fields trade speed for accuracy: cube-map resolution, sample
//! density, ε, the blend and its power N, Monte Carlo samples M, the cache. This crate measures
//! that trade on a user's own scene, against the ray-traced ground truth of
//! [`oslf_trace::ground_truth`], with the image metrics of [`metrics`] (RMSE in
//! CIELAB and linear RGB, PSNR; thesis §6.1).
//!
//! | module | what |
//! | --- | --- |
//! | [`metrics`] | image error: RMSE in CIELAB and linear RGB, PSNR, over a mask (thesis §6.1) |
//! | [`reference_noise`] | a path-traced reference's own noise, from two renders, and errors corrected for it |
//! | [`judge`] | render one runtime configuration, compare it with the truth, time it |
//! | [`table`] | result tables as aligned text, Markdown and CSV |
//! | [`pareto`] | the Pareto front of (time, error) |
//! | [`plot`] | the error-against-time plot with its front (PNG and SVG) |
//! | [`replay`] | renders a store along a camera path through the cache and sums its counters per phase (thesis §6.6) |
//! | [`cache_stats`] | the cache replays' rows as CSV and as a table |
//! | [`sweep`] | bake variants of a scene, judge every variant with every runtime setting |
//! | [`sweep_report`] | the sweep's Pareto fronts, its tables and the panels of its plot |
//! | [`thesis_tables`] | the thesis's Tables 6.1 and 6.2 and the Ashikhmin–Shirley table on a scene |
//!
//! Commands: `oslf tables` reproduces the thesis's Tables 6.1 and 6.2 and a new
//! Ashikhmin–Shirley table on a scene; `oslf sweep` runs the speed/accuracy sweep and the
//! sensitivity analysis (thesis §8.1.1) and draws the plot. The cache-statistics tool is the
//! `oslf cache-stats`.

pub mod cache_stats;
pub mod error;
pub mod judge;
pub mod metrics;
pub mod pareto;
pub mod plot;
pub mod reference_noise;
pub mod replay;
pub mod series_plot;
pub mod sweep;
pub mod sweep_report;
pub mod table;
pub mod thesis_tables;

pub use error::{MeasureError, Result};
