//! Helpers shared by arealight's example programs (the binaries of this package): output folder,
//! tone mapping and PNG, camera and ray casting, progress line, argument parsing.

pub mod image;
pub mod progress;
pub mod trace;

use std::path::{Path, PathBuf};

use arealight::glam::DVec3;

/// `rel` (a path relative to the repository's root, such as `scenes/cornell_box.gltf`) as an
/// absolute path: this package is the repository's `demo/` folder.
pub fn repo_path(rel: &str) -> PathBuf {
    let demo = Path::new(env!("CARGO_MANIFEST_DIR"));
    demo.parent().unwrap_or(demo).join(rel)
}

/// The published Cornell box camera (metres): eye, target, up, vertical field of view
/// (35 mm focal length on 25 mm film: `2 atan(12.5 / 35)`).
pub fn cornell_camera() -> (DVec3, DVec3, DVec3, f64) {
    (
        DVec3::new(0.278, 0.273, -0.8),
        DVec3::new(0.278, 0.273, 0.0),
        DVec3::Y,
        2.0 * (12.5f64 / 35.0).atan().to_degrees(),
    )
}

/// `x,y,z` as a vector.
pub fn parse_vec(s: &str) -> Result<DVec3, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>().map_err(|e| format!("{s:?}: {e}")))
        .collect::<Result<_, _>>()?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(DVec3::new(*x, *y, *z)),
        _ => Err(format!("{s:?}: expected x,y,z")),
    }
}

/// Runs `f` on a rayon pool of `threads` workers (0: rayon's global pool, all cores).
pub fn with_threads<T: Send>(
    threads: usize,
    f: impl FnOnce() -> Result<T, String> + Send,
) -> Result<T, String> {
    if threads == 0 {
        return f();
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| e.to_string())?
        .install(f)
}

/// The parsed command line, or, for a usage error, its message on stderr and exit status 2.
pub fn args_or_exit<A>(parsed: Result<A, String>) -> A {
    parsed.unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(2)
    })
}

/// Runs `run` on `threads` workers ([`with_threads`]); an error goes to stderr as
/// `name: error` with exit status 1.
pub fn run_or_exit(name: &str, threads: usize, run: impl FnOnce() -> Result<(), String> + Send) {
    if let Err(e) = with_threads(threads, run) {
        eprintln!("{name}: {e}");
        std::process::exit(1);
    }
}
