//! `cargo bench`: the three reference scenes on the CPU backend and, when an adapter exists, on
//! the GPU, at 256x256 and 64 spp: the same run as `hexray bench` with its defaults, which also
//! writes the JSON report (`out/bench.json`). Warm-up (kernel compilation, first pass) is
//! timed apart and not part of the rates.

use hexray::analysis::bench::{run, table, Config, Which};
use std::path::PathBuf;

fn main() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let gpu = match hexray::gpu::acquire(None) {
        Ok(g) => Some(g),
        Err(e) => {
            eprintln!("no GPU row: {e}");
            None
        }
    };
    let mut backends = vec![Which::Cpu];
    if gpu.is_some() {
        backends.push(Which::Gpu);
    }
    let config = Config {
        scenes: ["tncg15_room", "cornell_box", "glass_room"]
            .iter()
            .map(|s| root.join(format!("scenes/{s}.json")))
            .collect(),
        backends,
        width: 256,
        height: 256,
        spp: 64,
        seed: 1,
        methods: vec![hexray::transport::method::Method::Path],
        samplers: vec![hexray::math::sampling::SamplerKind::Independent],
        light_samples: 1,
        threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let report = run(&config, gpu.as_ref(), |_| {}).expect("benchmark");
    print!("{}", table(&report));
}
