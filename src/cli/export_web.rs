//! `oslf export-web`: the web viewer's site of one store ([`super::web_site`]) as static
//! files, for any static host: the page, the runtime's shaders, the manifest, the buffers and
//! every cube in every encoding a page may ask for.

use anyhow::bail;

use super::paths::{InputPath, OutputDir};
use super::serve::{human_bytes, open_site_store, WebCacheArgs};
use super::web_site::Site;

/// Write a store's web viewer as static files (index.html, oslf-viewer.js, shaders, the
/// store's data): publish a baked object on any static web host.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The store (written by `oslf bake`).
    store: InputPath,
    /// The directory to write; it must be absent or empty (nothing in it is replaced).
    dir: OutputDir,
    #[command(flatten)]
    access: super::args::StoreAccessArgs,
    #[command(flatten)]
    cache: WebCacheArgs,
    /// No progress bar.
    #[arg(short, long)]
    quiet: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let mut door = oslf_util::door::Door::new();
    door.input("STORE", &args.store)
        .output_dir("DIR", &args.dir);
    door.check()?;
    if let Ok(mut entries) = std::fs::read_dir(&*args.dir) {
        if entries.next().is_some() {
            bail!(
                "{}: not empty; export-web writes into an absent or empty directory, so that \
                 nothing already there is replaced",
                args.dir.display()
            );
        }
    }
    let site = Site::new(vec![open_site_store(
        &args.store,
        &args.access,
        &args.cache,
    )?]);
    let paths = site.paths();
    let bar = (!args.quiet).then(|| {
        let bar = indicatif::ProgressBar::new(paths.len() as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} files {bar:40} {pos}/{len} [{elapsed_precise} < ETA {eta_precise}]",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar
    });
    let mut total = 0u64;
    for path in &paths {
        let reply = site.get(path);
        if reply.status != 200 {
            bail!(
                "{}: {} (nothing more written; {} holds what was)",
                path,
                String::from_utf8_lossy(&reply.body),
                args.dir.display()
            );
        }
        let file = args.dir.join(path);
        door.check_output_in_dir("a file of DIR", &file)?;
        if let Some(parent) = file.parent() {
            std::fs::create_dir_all(parent)?;
        }
        oslf_util::output_file::write_bytes(&file, &reply.body)?;
        total += reply.body.len() as u64;
        if let Some(bar) = &bar {
            bar.inc(1);
        }
    }
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let m = site.stores()[0].web.manifest();
    println!(
        "wrote          {}: {} files, {} ({:.2}× the store's {}; cubes as {})",
        args.dir.display(),
        paths.len(),
        human_bytes(total),
        total as f64 / m.store_bytes.max(1) as f64,
        human_bytes(m.store_bytes),
        m.encodings().join(" and ")
    );
    println!(
        "publish        serve {} from any static web host and open index.html in a browser with WebGPU",
        args.dir.display()
    );
    Ok(())
}
