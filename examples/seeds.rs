use hexray::{
    camera::Camera,
    cpu::{render_pass, Faults},
    film::Film,
    flat::FlatScene,
    scene::Scene,
};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = Scene::load(std::path::Path::new(&args[1])).unwrap();
    let res: u32 = args[2].parse().unwrap();
    let spp: u32 = args[3].parse().unwrap();
    let flat = FlatScene::build(&scene);
    let cam = Camera::new(&scene.desc.camera, res, res);
    let mut ms = vec![];
    let mut ses = vec![];
    for seed in 100..140u32 {
        let mut film = Film::new(res, res);
        render_pass(&flat, &cam, seed, 0, spp, Faults::NONE, &mut film);
        let (m, se) = film.image_mean();
        ms.push(m[0]);
        ses.push(se[0]);
    }
    let n = ms.len() as f64;
    let mean = ms.iter().sum::<f64>() / n;
    let sd = (ms.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0)).sqrt();
    let se_avg = (ses.iter().map(|s| s * s).sum::<f64>() / n).sqrt();
    println!("mean {mean:.6} (+- {:.2e}) sd across seeds {sd:.3e} avg claimed s.e. {se_avg:.3e} ratio {:.3}", sd / n.sqrt(), sd/se_avg);
}
