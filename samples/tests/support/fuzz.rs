//! The glTF loader under mutated files: a valid file written by a test, its JSON changed at
//! random (a number replaced by an edge value, a member removed, an array emptied), loaded
//! again. Every mutant must load or be refused with an error; none may panic.
use hybrid_rt_host::scene::Rng;
use hybrid_rt_host::Host;
use hybrid_rt_samples::gltf_scene;
use hybrid_rt_samples::renderer::{Renderer, Settings};
use hybrid_rt_samples::scene::SampleScene;
use serde_json::Value;
use std::path::Path;

/// Numbers that break assumptions: negatives, zero, past the ends of buffers, huge.
const EDGE_NUMBERS: [f64; 9] = [-1.0, 0.0, 1.0, 2.0, 3.0, 65535.0, 4294967295.0, 1e30, -1e30];

/// Every place in `v` a mutation may touch: (path of keys and indices, is it a number).
fn places(v: &Value, path: &mut Vec<Value>, out: &mut Vec<(Vec<Value>, bool)>) {
    match v {
        Value::Object(m) => {
            for (k, child) in m {
                path.push(Value::String(k.clone()));
                out.push((path.clone(), child.is_number()));
                places(child, path, out);
                path.pop();
            }
        }
        Value::Array(a) => {
            for (i, child) in a.iter().enumerate() {
                path.push(Value::from(i));
                out.push((path.clone(), child.is_number()));
                places(child, path, out);
                path.pop();
            }
        }
        _ => {}
    }
}

/// The parent of `path`'s last step and that step.
fn parent<'a>(root: &'a mut Value, path: &[Value]) -> Option<(&'a mut Value, Value)> {
    let (last, up) = path.split_last()?;
    let mut v = root;
    for step in up {
        v = match step {
            Value::String(k) => v.get_mut(k.as_str())?,
            _ => v.get_mut(step.as_u64()? as usize)?,
        };
    }
    Some((v, last.clone()))
}

/// Loads `iterations` mutants of `file` (one to three mutations each, from `seed`); panics,
/// naming the mutation, if the loader panics on one. The first `rendered` mutants that load
/// are rendered (two frames, 32x24) on `host`: that may fail with an error, never panic.
/// Returns (loaded, refused).
pub fn fuzz_loader(file: &Path, iterations: usize, seed: u64, host: &Host, rendered: usize) -> (usize, usize) {
    let original: Value = serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
    let mut all = Vec::new();
    places(&original, &mut Vec::new(), &mut all);
    let mut rng = Rng::new(seed);
    let mut pick = |n: usize| ((rng.next_f32() * n as f32) as usize).min(n - 1);
    let (mut loaded, mut refused) = (0, 0);
    let mutant = file.with_extension("mutant.gltf");
    for it in 0..iterations {
        let mut v = original.clone();
        let mut said = Vec::new();
        for _ in 0..1 + pick(3) {
            let (path, is_number) = &all[pick(all.len())];
            let Some((p, step)) = parent(&mut v, path) else { continue };
            let kind = pick(3);
            let target = match &step {
                Value::String(k) => p.get_mut(k.as_str()),
                _ => p.get_mut(step.as_u64().unwrap_or(0) as usize),
            };
            match (kind, target) {
                (0, Some(t)) if *is_number => {
                    let n = EDGE_NUMBERS[pick(EDGE_NUMBERS.len())];
                    said.push(format!("{path:?} = {n}"));
                    *t = serde_json::Number::from_f64(n).map_or(Value::Null, Value::Number);
                }
                (1, Some(Value::Array(a))) => {
                    said.push(format!("{path:?} emptied"));
                    a.clear();
                }
                (_, Some(_)) => {
                    if let (Value::Object(m), Value::String(k)) = (&mut *p, &step) {
                        said.push(format!("{path:?} removed"));
                        m.remove(k);
                    }
                }
                _ => {}
            }
        }
        std::fs::write(&mutant, serde_json::to_string(&v).unwrap()).unwrap();
        match std::panic::catch_unwind(|| gltf_scene::load(&mutant)) {
            Ok(Ok(scene)) => {
                if loaded < rendered {
                    let run = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| render(host, scene)));
                    let Ok(worked) = run else { panic!("mutant {it} of {}: rendering panicked on {said:?}", file.display()) };
                    eprintln!("mutant {it} rendered: {}", if worked { "yes" } else { "no (an error)" });
                }
                loaded += 1
            }
            Ok(Err(_)) => refused += 1,
            Err(_) => panic!("mutant {it} of {}: the loader panicked on {said:?}", file.display()),
        }
    }
    (loaded, refused)
}

/// Two frames of `scene` at 32x24; whether it worked (an error is an answer too).
fn render(host: &Host, scene: SampleScene) -> bool {
    let settings = Settings { width: 32, height: 24, lidar_size: 16, ..Default::default() };
    let Ok(mut r) = Renderer::new(host, scene, settings) else { return false };
    let camera = r.scene.camera_path.at(0.5);
    let ok = (0..2).all(|f| r.render(camera, f as f32 / 30.0, &[], None).is_ok());
    r.destroy().is_ok() && ok
}
