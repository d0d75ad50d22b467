//! The web viewer's site, one tree of paths that `oslf serve` answers over HTTP and `oslf
//! export-web` writes as files: the page (`web/index.html`, `web/oslf-viewer.js`), the
//! runtime's own shaders, and per store its manifest and bytes ([`oslf_runtime::web`]).
//!
//! | path | what |
//! |---|---|
//! | `index.html` (and `/`) | the page: an `<oslf-viewer>` of the first store, or of `?store=N` |
//! | `oslf-viewer.js` | the web component |
//! | `shaders/gbuffer.wgsl`, `shaders/shade.wgsl` | the runtime's shaders as it compiles them |
//! | `shaders/blit.wgsl` | `oslf view`'s tone mapping (as the PNGs of `oslf render`) |
//! | `stores.json` | the stores: name and path of each |
//! | `stores/N/manifest.json` | store N's [`oslf_runtime::web::WebManifest`] |
//! | `stores/N/NAME.bin` | its resources ([`WebStore::resource`]) |
//! | `stores/N/cubes/ENCODING/C.bin` | its cube C in an encoding of the manifest ([`WebStore::cube`]) |

use oslf_runtime::web::{WebStore, GBUFFER_WGSL, SHADE_WGSL};
use xxhash_rust::xxh3::xxh3_64;

const INDEX_HTML: &str = include_str!("../../web/index.html");
const VIEWER_JS: &str = include_str!("../../web/oslf-viewer.js");
const BLIT_WGSL: &str = include_str!("../../generated/view_blit.wgsl");

/// One store of the site.
pub struct SiteStore {
    /// What the store is called.
    pub name: String,
    /// The store, opened for the page.
    pub web: WebStore,
    /// Identifies this store's bytes (its path, size and modification time) for ETags.
    pub stamp: u64,
}

/// The site of some stores.
pub struct Site {
    stores: Vec<SiteStore>,
    /// [`page_stamp`], hashed once.
    page: u64,
}

/// What a path answers.
pub struct Reply {
    /// HTTP status: 200, 404 (no such path), 500 (the store's bytes are damaged).
    pub status: u16,
    /// MIME type of the body.
    pub content_type: &'static str,
    /// The body: the content, or for an error its message as plain text.
    pub body: Vec<u8>,
    /// An entity tag that changes when the body can change (200 only).
    pub etag: Option<String>,
}

impl Reply {
    /// A 200 of `body`, tagged by `stamp` and the body's name.
    fn ok(content_type: &'static str, body: Vec<u8>, stamp: u64) -> Reply {
        Reply {
            status: 200,
            content_type,
            body,
            etag: Some(format!("\"{stamp:016x}\"")),
        }
    }

    /// An error reply whose body says why.
    fn error(status: u16, message: String) -> Reply {
        Reply {
            status,
            content_type: "text/plain; charset=utf-8",
            body: message.into_bytes(),
            etag: None,
        }
    }
}

/// A hash of the page's own files, so that a new `oslf` changes every ETag.
fn page_stamp() -> u64 {
    xxh3_64(
        [INDEX_HTML, VIEWER_JS, BLIT_WGSL, GBUFFER_WGSL, SHADE_WGSL]
            .concat()
            .as_bytes(),
    )
}

impl Site {
    /// The site of `stores`, numbered in order.
    pub fn new(stores: Vec<SiteStore>) -> Site {
        Site {
            stores,
            page: page_stamp(),
        }
    }

    /// The stores.
    pub fn stores(&self) -> &[SiteStore] {
        &self.stores
    }

    /// Every path of the site (without the leading `/`), cubes of every encoding included:
    /// what `oslf export-web` writes.
    pub fn paths(&self) -> Vec<String> {
        let mut paths: Vec<String> = [
            "index.html",
            "oslf-viewer.js",
            "shaders/gbuffer.wgsl",
            "shaders/shade.wgsl",
            "shaders/blit.wgsl",
            "stores.json",
        ]
        .map(String::from)
        .to_vec();
        for (i, s) in self.stores.iter().enumerate() {
            paths.push(format!("stores/{i}/manifest.json"));
            for name in s.web.resource_names() {
                paths.push(format!("stores/{i}/{name}"));
            }
            let m = s.web.manifest();
            for v in &m.variants {
                for c in 0..m.cube_count {
                    paths.push(format!("stores/{i}/cubes/{}/{c}.bin", v.encoding));
                }
            }
        }
        paths
    }

    /// The reply to a GET of `path` (its query, if any, already removed).
    pub fn get(&self, path: &str) -> Reply {
        let path = path.trim_start_matches('/');
        let page = self.page;
        let text = |t: &'static str| t.as_bytes().to_vec();
        match path {
            "" | "index.html" => Reply::ok("text/html; charset=utf-8", text(INDEX_HTML), page),
            "oslf-viewer.js" => Reply::ok("text/javascript; charset=utf-8", text(VIEWER_JS), page),
            "shaders/gbuffer.wgsl" => {
                Reply::ok("text/wgsl; charset=utf-8", text(GBUFFER_WGSL), page)
            }
            "shaders/shade.wgsl" => Reply::ok("text/wgsl; charset=utf-8", text(SHADE_WGSL), page),
            "shaders/blit.wgsl" => Reply::ok("text/wgsl; charset=utf-8", text(BLIT_WGSL), page),
            "stores.json" => {
                let list: Vec<serde_json::Value> = self
                    .stores
                    .iter()
                    .enumerate()
                    .map(
                        |(i, s)| serde_json::json!({"name": s.name, "src": format!("stores/{i}/")}),
                    )
                    .collect();
                let stamp = self.stores.iter().fold(page, |h, s| h ^ s.stamp);
                Reply::ok(
                    "application/json",
                    serde_json::to_vec(&list).unwrap_or_default(),
                    stamp,
                )
            }
            _ => self.store_path(path, page),
        }
    }

    /// A path under `stores/N/`.
    fn store_path(&self, path: &str, page: u64) -> Reply {
        let not_found = || Reply::error(404, format!("/{path}: no such file on this server"));
        let Some(rest) = path.strip_prefix("stores/") else {
            return not_found();
        };
        let Some((index, rest)) = rest.split_once('/') else {
            return not_found();
        };
        let Some(store) = index.parse::<usize>().ok().and_then(|i| self.stores.get(i)) else {
            return Reply::error(
                404,
                format!(
                    "/{path}: no store {index} (this server has {})",
                    self.stores.len()
                ),
            );
        };
        let stamp = store.stamp ^ page;
        let damaged =
            |e: oslf_runtime::RuntimeError| Reply::error(500, format!("{}: {e}", store.name));
        if rest == "manifest.json" {
            return match serde_json::to_vec(store.web.manifest()) {
                Ok(body) => Reply::ok("application/json", body, stamp),
                Err(e) => Reply::error(500, format!("{}: manifest: {e}", store.name)),
            };
        }
        if let Some(cube) = rest.strip_prefix("cubes/") {
            let Some((encoding, file)) = cube.split_once('/') else {
                return not_found();
            };
            let Some(index) = file
                .strip_suffix(".bin")
                .and_then(|c| c.parse::<u32>().ok())
            else {
                return not_found();
            };
            return match store.web.cube(index, encoding) {
                Ok(body) => Reply::ok("application/octet-stream", body, stamp ^ u64::from(index)),
                Err(oslf_runtime::RuntimeError::Parameter(m)) => {
                    Reply::error(404, format!("/{path}: {m}"))
                }
                Err(e) => damaged(e),
            };
        }
        match store.web.resource(rest) {
            Ok(Some(body)) => Reply::ok("application/octet-stream", body, stamp),
            Ok(None) => not_found(),
            Err(e) => damaged(e),
        }
    }
}

/// A stamp of the store file at `path`: its canonical path, size and modification time.
pub fn file_stamp(path: &std::path::Path) -> u64 {
    let canonical = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    let meta = std::fs::metadata(path).ok();
    let size = meta.as_ref().map_or(0, |m| m.len());
    let modified = meta
        .and_then(|m| m.modified().ok())
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos() as u64);
    let mut bytes = canonical.to_string_lossy().into_owned().into_bytes();
    bytes.extend(size.to_le_bytes());
    bytes.extend(modified.to_le_bytes());
    xxh3_64(&bytes)
}
