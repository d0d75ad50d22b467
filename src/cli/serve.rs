//! `oslf serve`: the web viewer on localhost. Serves the page, the runtime's shaders and each
//! store's manifest, buffers and cube maps ([`super::web_site`]) over HTTP/1.1 with tiny_http;
//! the page streams the cubes it needs, one URL per cube.

use std::sync::Arc;

use anyhow::{bail, Context};
use oslf_runtime::cache;
use oslf_runtime::web::WebStore;
use oslf_runtime::CacheConfig;

use super::paths::InputPath;
use super::web_site::{file_stamp, Reply, Site, SiteStore};

/// Serve stores to a web browser: `<oslf-viewer>`, a WebGPU page that draws them with the
/// runtime's own shaders, streaming cube maps on demand.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The stores (written by `oslf bake`); the page shows the first, `?store=N` another.
    #[arg(required = true)]
    stores: Vec<InputPath>,
    #[command(flatten)]
    access: super::args::StoreAccessArgs,
    #[command(flatten)]
    cache: WebCacheArgs,
    /// TCP port on the host (0: any free port; the URL printed says which).
    #[arg(long, default_value_t = 8080)]
    port: u16,
    /// Address to listen on (127.0.0.1: this machine only).
    #[arg(long, default_value = "127.0.0.1")]
    host: String,
    /// Open the page in the desktop's browser (`xdg-open`, `open` on macOS).
    #[arg(long)]
    open: bool,
    /// Print one line per request (method, path, status, bytes).
    #[arg(long)]
    log: bool,
}

/// The page's GPU cache budget.
#[derive(clap::Args, Debug, Clone)]
pub struct WebCacheArgs {
    /// GPU cache budget of the page in cube-map slots [default: every cube, up to 1 GiB].
    #[arg(long, conflicts_with = "cache_mb")]
    pub cache_slots: Option<u32>,
    /// GPU cache budget of the page in MB of cube-map texels (as RGB9E5, the larger
    /// encoding a page may use).
    #[arg(long)]
    pub cache_mb: Option<f64>,
}

/// Opens the store at `path` for the page, with the cache budget of `cache`.
pub fn open_site_store(
    path: &InputPath,
    access: &super::args::StoreAccessArgs,
    cache: &WebCacheArgs,
) -> anyhow::Result<SiteStore> {
    let store = access.open(path)?;
    let gpu_slots = match (cache.cache_slots, cache.cache_mb) {
        (Some(s), _) => Some(s),
        (None, Some(mb)) => Some(cache::slots_for_megabytes(&store, mb, false)?),
        (None, None) => None,
    };
    let config = CacheConfig {
        gpu_slots,
        ..Default::default()
    };
    let name = path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    let web = WebStore::new(store, &name, bytes, &config)
        .with_context(|| format!("cannot prepare {} for the web page", path.display()))?;
    Ok(SiteStore {
        name,
        web,
        stamp: file_stamp(path),
    })
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let mut door = oslf_util::door::Door::new();
    for s in &args.stores {
        door.input("STORE", s);
    }
    door.check()?;
    let stores = args
        .stores
        .iter()
        .map(|p| open_site_store(p, &args.access, &args.cache))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let site = Arc::new(Site::new(stores));
    let server = tiny_http::Server::http((args.host.as_str(), args.port))
        .map_err(|e| anyhow::anyhow!("cannot listen on {}:{}: {e}", args.host, args.port))?;
    let Some(addr) = server.server_addr().to_ip() else {
        bail!("the server has no IP address");
    };
    let url = format!("http://{addr}/");
    for (i, s) in site.stores().iter().enumerate() {
        let m = s.web.manifest();
        println!(
            "store {i}        {}: {} cubes, {} sample maps, {} as {}",
            s.name,
            m.cube_count,
            m.map_count,
            human_bytes(m.store_bytes),
            m.encodings().join(" or ")
        );
    }
    println!("serving        {url} (Ctrl-C stops)");
    use std::io::Write;
    std::io::stdout().flush()?;
    if args.open {
        open_browser(&url);
    }
    let server = Arc::new(server);
    let workers: Vec<_> = (0..4)
        .map(|_| {
            let (server, site) = (server.clone(), site.clone());
            std::thread::spawn(move || serve_requests(&server, &site, args.log))
        })
        .collect();
    for w in workers {
        let _ = w.join();
    }
    Ok(())
}

/// Answers requests until the server stops.
fn serve_requests(server: &tiny_http::Server, site: &Site, log: bool) {
    while let Ok(request) = server.recv() {
        let url = request.url().to_string();
        let path = url.split(['?', '#']).next().unwrap_or("");
        let method = request.method().clone();
        let reply = match method {
            tiny_http::Method::Get | tiny_http::Method::Head => site.get(path),
            _ => Reply {
                status: 405,
                content_type: "text/plain; charset=utf-8",
                body: format!("{method} {path}: only GET and HEAD").into_bytes(),
                etag: None,
            },
        };
        let if_none_match = request
            .headers()
            .iter()
            .find(|h| h.field.equiv("If-None-Match"))
            .map(|h| h.value.as_str().to_string());
        let fresh = reply.etag.is_some() && reply.etag == if_none_match;
        let status = if fresh { 304 } else { reply.status };
        if log {
            eprintln!("{method} {path} {status} {} bytes", reply.body.len());
        }
        let mut response =
            tiny_http::Response::from_data(if fresh { Vec::new() } else { reply.body })
                .with_status_code(status)
                // Content-Length, never chunked: every body is in memory, and a browser then knows
                // each response's size (tiny_http chunks bodies over 32 KB by default).
                .with_chunked_threshold(usize::MAX);
        let mut header = |name: &str, value: &str| {
            if let Ok(h) = tiny_http::Header::from_bytes(name.as_bytes(), value.as_bytes()) {
                response.add_header(h);
            }
        };
        header("Content-Type", reply.content_type);
        // Revalidated on every load: a store baked again at the same path changes its tag.
        header("Cache-Control", "no-cache");
        if let Some(tag) = &reply.etag {
            header("ETag", tag);
        }
        let _ = request.respond(response);
    }
}

/// Opens `url` in the desktop's browser, or says how to.
fn open_browser(url: &str) {
    let opener = if cfg!(target_os = "macos") {
        "open"
    } else {
        "xdg-open"
    };
    if let Err(e) = std::process::Command::new(opener).arg(url).spawn() {
        eprintln!("note: cannot start {opener} ({e}); open {url} in a browser with WebGPU");
    }
}

/// `n` bytes in KB, MB or GB.
pub fn human_bytes(n: u64) -> String {
    let n = n as f64;
    if n >= 1e9 {
        format!("{:.2} GB", n / 1e9)
    } else if n >= 1e6 {
        format!("{:.1} MB", n / 1e6)
    } else {
        format!("{:.1} KB", n / 1e3)
    }
}
