//! The subcommands of `oslf`, one module each, and the shared flags ([`args`]).

pub mod args;
mod bake;
mod cache_stats;
mod compare;
mod completions;
mod device;
mod export_web;
mod flags;
mod paths;
mod progress;
mod render;
mod serve;
mod store;
mod sweep;
mod tables;
mod truth;
mod view;
mod web_site;

use clap::{Parser, Subcommand};

/// Offset surface light fields: bake position-dependent reflections of a scene into a store,
/// render them with wgpu, and measure them against ray-traced ground truth.
#[derive(Parser, Debug)]
#[command(name = "oslf", version, propagate_version = true)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Bake a scene file into a store: sample points ε above the object's Bézier patches, a
    /// ray-traced HDR cube map at each, per-patch sample maps.
    Bake(bake::Args),
    /// Render a store headless to OpenEXR (linear RGB, alpha = object mask) and a PNG preview.
    Render(render::Args),
    /// Open a window and orbit around a store's object interactively.
    View(view::Args),
    /// Inspect, verify and export stores.
    Store(store::Args),
    /// Ray-trace the ground truth of what each runtime mode approximates.
    Truth(truth::Args),
    /// Compare two OpenEXR images: RMSE in CIELAB and linear RGB, and PSNR, over a mask.
    Compare(compare::Args),
    /// Reproduce the thesis's Tables 6.1 and 6.2 (and an Ashikhmin–Shirley table) on a scene.
    Tables(tables::Args),
    /// Sweep bake and shading settings: error against frame time, Pareto front, plot.
    Sweep(sweep::Args),
    /// Replay a still view and an orbit and report the cube-map cache's hits, misses and loads.
    CacheStats(cache_stats::Args),
    /// Serve stores to a browser: a WebGPU page that draws them with the runtime's shaders.
    Serve(serve::Args),
    /// Write a store's web viewer as static files for any web host.
    ExportWeb(export_web::Args),
    /// Print a shell completion script (bash, zsh, fish, elvish, powershell) to stdout.
    Completions(completions::Args),
}

/// Runs the chosen subcommand.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    let result = match cli.command {
        Command::Bake(a) => bake::run(a),
        Command::Render(a) => render::run(a),
        Command::View(a) => view::run(a),
        Command::Store(a) => store::run(a),
        Command::Truth(a) => truth::run(a),
        Command::Compare(a) => compare::run(a),
        Command::Tables(a) => tables::run(a),
        Command::Sweep(a) => sweep::run(a),
        Command::CacheStats(a) => cache_stats::run(a),
        Command::Serve(a) => serve::run(a),
        Command::ExportWeb(a) => export_web::run(a),
        Command::Completions(a) => completions::run(a),
    };
    result.map_err(flags::name_flags)
}

#[cfg(all(test, unix))]
mod door_tests;

#[cfg(test)]
mod tests {
    use super::Cli;
    use clap::CommandFactory;

    #[test]
    fn command_tree_is_consistent() {
        Cli::command().debug_assert();
    }
}
