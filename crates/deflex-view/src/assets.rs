//! The page and its vendored libraries, compiled into the binary (nothing is read from disk or
//! fetched from outside at run time).

/// One file the server answers with.
pub struct Asset {
    /// URL path.
    pub path: &'static str,
    /// `Content-Type`.
    pub content_type: &'static str,
    /// Body.
    pub body: &'static [u8],
}

const JS: &str = "text/javascript; charset=utf-8";
const CSS: &str = "text/css; charset=utf-8";
const TEXT: &str = "text/plain; charset=utf-8";

/// Every file served.
pub const ASSETS: &[Asset] = &[
    Asset {
        path: "/",
        content_type: "text/html; charset=utf-8",
        body: include_bytes!("../assets/index.html"),
    },
    Asset {
        path: "/app.js",
        content_type: JS,
        body: include_bytes!("../assets/app.js"),
    },
    Asset {
        path: "/style.css",
        content_type: CSS,
        body: include_bytes!("../assets/style.css"),
    },
    Asset {
        path: "/vendor/uplot/uPlot.iife.min.js",
        content_type: JS,
        body: include_bytes!("../assets/vendor/uplot/uPlot.iife.min.js"),
    },
    Asset {
        path: "/vendor/uplot/uPlot.min.css",
        content_type: CSS,
        body: include_bytes!("../assets/vendor/uplot/uPlot.min.css"),
    },
    Asset {
        path: "/vendor/uplot/LICENSE",
        content_type: TEXT,
        body: include_bytes!("../assets/vendor/uplot/LICENSE"),
    },
    Asset {
        path: "/vendor/three/three.module.min.js",
        content_type: JS,
        body: include_bytes!("../assets/vendor/three/three.module.min.js"),
    },
    Asset {
        path: "/vendor/three/three.core.min.js",
        content_type: JS,
        body: include_bytes!("../assets/vendor/three/three.core.min.js"),
    },
    Asset {
        path: "/vendor/three/OrbitControls.js",
        content_type: JS,
        body: include_bytes!("../assets/vendor/three/OrbitControls.js"),
    },
    Asset {
        path: "/vendor/three/LICENSE",
        content_type: TEXT,
        body: include_bytes!("../assets/vendor/three/LICENSE"),
    },
    Asset {
        path: "/vendor/VENDORED.md",
        content_type: TEXT,
        body: include_bytes!("../assets/vendor/VENDORED.md"),
    },
];

/// The asset at `path` (query string ignored).
pub fn find(path: &str) -> Option<&'static Asset> {
    let path = path.split(['?', '#']).next().unwrap_or(path);
    let path = if path == "/index.html" { "/" } else { path };
    ASSETS.iter().find(|a| a.path == path)
}
