//! Surfel layouts of a geometry built on the CPU from its vertices and indices: the
//! specification the GPU builder (`passes::surfel_layout`, which every geometry that fits its
//! dispatches uses) is tested against, and the fallback for a mesh too big for it (read back
//! once, when the ticket that copied it returns — no stall). Shaders read layouts through
//! shaders/include/cache.glsl; the builders and it must agree word for word.
use crate::types::{SurfelSettings, SurfelType};
use glam::Vec3;
use std::collections::HashMap;

/// Largest resolution along an edge (the layout packs it in 9 bits).
pub use crate::types::MAX_TILE_RESOLUTION as MAX_RESOLUTION;

#[derive(Debug, Clone)]
pub(crate) struct SurfelLayout {
    pub surfel_type: SurfelType,
    /// Words as the shader reads them (per triangle: 2 for tiles, 9 for mesh colors).
    pub words: Vec<u32>,
    pub sample_count: u32,
    /// Largest per-triangle resolution (sizes the transfer pass's launch).
    pub max_resolution: u32,
}

/// Samples along the longest edge: edge length / unit, at least 1, at most the limit.
pub(crate) fn resolution(tri: [Vec3; 3], s: &SurfelSettings) -> u32 {
    let longest = (0..3).map(|k| tri[k].distance(tri[(k + 1) % 3])).fold(0.0f32, f32::max);
    let r = (longest / s.tile_unit_length).ceil();
    (if r.is_finite() { r as u32 } else { 1 }).clamp(1, s.tile_resolution_limit.clamp(1, MAX_RESOLUTION))
}

/// The layout of a geometry, with at most `max_samples` samples: a layout that would need more
/// (a huge mesh at a fine resolution) is built again at half the resolution limit until it
/// fits, so a sample index never wraps and no cache outgrows what one buffer can hold. None
/// when even one sample per edge is too many (the geometry then has no cache).
pub(crate) fn build(positions: &[Vec3], triangles: &[[u32; 3]], s: &SurfelSettings, max_samples: u64) -> Option<SurfelLayout> {
    let max_samples = max_samples.min(u32::MAX as u64);
    let mut settings = *s;
    if s.maps_directly_from_start() {
        // Forced: one sample per triangle from the start.
        settings.tile_resolution_limit = 1;
    }
    loop {
        let layout = match settings.surfel_type {
            SurfelType::Tiles => tiles(positions, triangles, &settings, max_samples),
            SurfelType::MeshColors => mesh_colors(positions, triangles, &settings, max_samples),
        };
        match layout {
            // Nearly one sample per triangle already: exactly one (direct tile mapping).
            Some(l) if settings.tile_resolution_limit > 1 && s.maps_directly(triangles.len() as u64, l.sample_count as u64) => {
                settings.tile_resolution_limit = 1;
            }
            Some(l) => {
                if settings.tile_resolution_limit != s.tile_resolution_limit
                    && !s.maps_directly(triangles.len() as u64, l.sample_count as u64)
                {
                    log::warn!(
                        "surfel layout of {} triangles: tile_resolution_limit {} needs more than {max_samples} samples; using {}",
                        triangles.len(),
                        s.tile_resolution_limit,
                        settings.tile_resolution_limit
                    );
                }
                return Some(l);
            }
            None if settings.tile_resolution_limit > 1 => settings.tile_resolution_limit /= 2,
            None => {
                log::error!("surfel layout of {} triangles needs more than {max_samples} samples: no cache", triangles.len());
                return None;
            }
        }
    }
}

fn corners(positions: &[Vec3], t: &[u32; 3]) -> [Vec3; 3] {
    t.map(|i| positions.get(i as usize).copied().unwrap_or(Vec3::ZERO))
}

/// An R x R tile of samples per triangle.
/// (Sample counts run in u64: offsets below the final count fit u32 once it is checked.)
fn tiles(positions: &[Vec3], triangles: &[[u32; 3]], s: &SurfelSettings, max_samples: u64) -> Option<SurfelLayout> {
    let mut words = Vec::with_capacity(triangles.len() * 2);
    let mut next = 0u64;
    let mut max_resolution = 1;
    for t in triangles {
        let r = resolution(corners(positions, t), s);
        max_resolution = max_resolution.max(r);
        words.extend_from_slice(&[next as u32, r]);
        next += (r * r) as u64;
        if next > max_samples {
            return None;
        }
    }
    Some(SurfelLayout { surfel_type: SurfelType::Tiles, words, sample_count: next as u32, max_resolution })
}

/// Interior lattice points of a triangle of resolution r.
pub(crate) fn interior_count(r: u32) -> u32 {
    if r < 3 {
        0
    } else {
        (r - 1) * (r - 2) / 2
    }
}

/// Mesh colors: one sample per distinct vertex position, r_e - 1 per edge (r_e: the finest
/// resolution of the triangles sharing it), and the interior lattice points per triangle.
fn mesh_colors(positions: &[Vec3], triangles: &[[u32; 3]], s: &SurfelSettings, max_samples: u64) -> Option<SurfelLayout> {
    // Samples are shared through the mesh's own topology (shared vertex indices), not by
    // position: engines split vertices at hard edges, and a cube's faces must not share
    // lighting across a 90-degree crease. (A UV seam that splits vertices of a smooth surface
    // keeps two rows of samples that injection fills alike.)
    let mut vertex_sample: HashMap<u32, u32> = HashMap::new();
    // Vertex samples number at most the distinct indices, so they fit u32.
    let mut next = 0u64;
    let mut weld = |i: u32, next: &mut u64| -> u32 {
        *vertex_sample.entry(i).or_insert_with(|| {
            *next += 1;
            (*next - 1) as u32
        })
    };
    let welded: Vec<[u32; 3]> = triangles.iter().map(|t| t.map(|i| weld(i, &mut next))).collect();
    let res: Vec<u32> = triangles.iter().map(|t| resolution(corners(positions, t), s)).collect();

    // Edges keyed by their (lower, higher) vertex samples; resolution = max of the faces.
    let mut edge_res: HashMap<(u32, u32), u32> = HashMap::new();
    for (t, &r) in welded.iter().zip(&res) {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let e = edge_res.entry((a.min(b), a.max(b))).or_insert(1);
            *e = (*e).max(r);
        }
    }
    let mut edge_base: HashMap<(u32, u32), u32> = HashMap::with_capacity(edge_res.len());
    // Deterministic order (sorted keys) so a layout does not depend on hash iteration.
    let mut keys: Vec<_> = edge_res.keys().copied().collect();
    keys.sort_unstable();
    for key in keys {
        edge_base.insert(key, next as u32);
        next += (edge_res[&key] - 1) as u64;
        if next > max_samples {
            return None;
        }
    }
    let mut words = Vec::with_capacity(triangles.len() * 9);
    for (t, &r) in welded.iter().zip(&res) {
        let mut e = [0u32; 3];
        let mut info = 0u32;
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            e[k] = edge_base[&key];
            let reversed = (a > b) as u32;
            info |= (edge_res[&key] | (reversed << 9)) << (10 * k);
        }
        let face = next as u32;
        next += interior_count(r) as u64;
        if next > max_samples {
            return None;
        }
        words.extend_from_slice(&[t[0], t[1], t[2], e[0], e[1], e[2], info, face, r]);
    }
    let max_resolution = res.iter().copied().max().unwrap_or(1);
    Some(SurfelLayout { surfel_type: SurfelType::MeshColors, words, sample_count: next as u32, max_resolution })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn build_all(p: &[Vec3], t: &[[u32; 3]], s: &SurfelSettings) -> SurfelLayout {
        build(p, t, s, u64::MAX).expect("fits")
    }

    /// 65,536 triangles x 256^2 tiles is 2^32 samples: the count must never wrap. Too many
    /// samples halve the resolution limit until the layout fits; too many even at one sample
    /// per edge leave the geometry without a cache.
    #[test]
    fn a_layout_over_the_sample_budget_is_coarsened_not_wrapped() {
        let (p, t) = quad();
        let fine = settings(SurfelType::Tiles, 0.01, 64);
        assert_eq!(build_all(&p, &t, &fine).sample_count, 2 * 64 * 64);
        let l = build(&p, &t, &fine, 1000).expect("coarsened");
        assert_eq!(l.sample_count, 2 * 16 * 16, "limit 64 -> 32 (2048 samples) -> 16 (512)");
        assert!(build(&p, &t, &fine, 1).is_none(), "two triangles never fit one sample");
        let colors = build(&p, &t, &settings(SurfelType::MeshColors, 0.01, 64), 500).expect("coarsened");
        assert!(colors.sample_count <= 500 && colors.max_resolution < 64, "{} samples", colors.sample_count);
        // A count past the budget is refused by the builders themselves, not wrapped.
        assert!(tiles(&p, &t, &settings(SurfelType::Tiles, 0.001, 256), 10_000).is_none());
    }

    fn settings(t: SurfelType, unit: f32, limit: u32) -> SurfelSettings {
        SurfelSettings { surfel_type: t, tile_unit_length: unit, tile_resolution_limit: limit, ..Default::default() }
    }

    /// A unit quad as two triangles sharing the diagonal (0, 2).
    fn quad() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        (vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, 1.0), Vec3::Z], vec![[0, 1, 2], [0, 2, 3]])
    }

    /// The CPU builder maps directly as the GPU passes do: nine unit-quad triangles of one
    /// sample and one of four (13 samples, 10 triangles: over 0.7) become ten samples; a
    /// threshold of 1 keeps 13; forcing maps a fine layout directly.
    #[test]
    fn tiles_near_one_sample_per_triangle_are_mapped_directly() {
        let mut p = Vec::new();
        let mut t = Vec::new();
        for k in 0..9 {
            let o = Vec3::new(2.0 * k as f32, 0.0, 0.0);
            let base = p.len() as u32;
            p.extend([o, o + Vec3::X, o + Vec3::Z]);
            t.push([base, base + 1, base + 2]);
        }
        let base = p.len() as u32;
        p.extend([Vec3::new(0.0, 0.0, 5.0), Vec3::new(2.0, 0.0, 5.0), Vec3::new(0.0, 0.0, 7.0)]);
        t.push([base, base + 1, base + 2]);
        let with = |unit: f32, force: bool, threshold: f32| {
            let s = SurfelSettings {
                force_direct_tile_mapping: force,
                direct_tile_mapping_threshold: threshold,
                ..settings(SurfelType::Tiles, unit, 64)
            };
            build(&p, &t, &s, u64::MAX).expect("fits")
        };
        assert_eq!(with(1.5, false, 1.0).sample_count, 13);
        let direct = with(1.5, false, 0.7);
        assert_eq!((direct.sample_count, direct.max_resolution), (10, 1));
        assert_eq!(direct.words.chunks(2).map(|w| w[0]).collect::<Vec<_>>(), (0..10).collect::<Vec<u32>>(), "sample = triangle");
        assert!(with(0.2, false, 0.7).sample_count > 100, "a fine layout is kept");
        assert_eq!(with(0.2, true, 0.7).sample_count, 10);
        // Mesh colors ignore both.
        let colors = SurfelSettings { force_direct_tile_mapping: true, ..settings(SurfelType::MeshColors, 0.2, 64) };
        assert!(build(&p, &t, &colors, u64::MAX).expect("fits").sample_count > 10);
    }

    #[test]
    fn tiles_hold_r_squared_samples_per_triangle() {
        let (p, t) = quad();
        // Longest edge is the diagonal, sqrt(2): 0.25 units per sample -> 6 samples along it.
        let l = build_all(&p, &t, &settings(SurfelType::Tiles, 0.25, 64));
        assert_eq!(l.words, vec![0, 6, 36, 6]);
        assert_eq!(l.sample_count, 72);
        let limited = build_all(&p, &t, &settings(SurfelType::Tiles, 0.25, 4));
        assert_eq!(limited.sample_count, 32);
    }

    #[test]
    fn mesh_colors_share_vertices_and_edges() {
        let (p, t) = quad();
        let l = build_all(&p, &t, &settings(SurfelType::MeshColors, 0.25, 64));
        let r = 6;
        // 4 vertices + 5 edges of (r - 1) + 2 interiors of (r-1)(r-2)/2.
        assert_eq!(l.sample_count, 4 + 5 * (r - 1) + 2 * interior_count(r));
        // The shared diagonal: triangle 0 runs 2 -> 0 on its edge 2, triangle 1 runs 0 -> 2
        // on its edge 0; same first sample, opposite directions.
        let w0 = &l.words[0..9];
        let w1 = &l.words[9..18];
        assert_eq!(w0[5], w1[3]);
        let dir = |info: u32, k: u32| (info >> (10 * k + 9)) & 1;
        assert_ne!(dir(w0[6], 2), dir(w1[6], 0));
        // Vertex samples are shared too.
        assert_eq!(w0[0], w1[0]);
        assert_eq!(w0[2], w1[1]);
    }

    #[test]
    fn split_vertices_do_not_share_samples() {
        // The same quad with the diagonal's vertices duplicated (a hard edge): the two
        // triangles keep separate vertex and edge samples.
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, 1.0), Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0), Vec3::Z];
        let t = vec![[0, 1, 2], [3, 4, 5]];
        let split = build_all(&p, &t, &settings(SurfelType::MeshColors, 0.25, 64));
        let (qp, qt) = quad();
        let shared = build_all(&qp, &qt, &settings(SurfelType::MeshColors, 0.25, 64));
        // Two more vertices and one more diagonal edge (r - 1 = 5 samples).
        assert_eq!(split.sample_count, shared.sample_count + 2 + 5);
    }

    #[test]
    fn memory_scales_with_inverse_square_unit_until_the_limit() {
        let (p, t) = quad();
        let count = |unit| build_all(&p, &t, &settings(SurfelType::Tiles, unit, 32)).sample_count as f32;
        let ratio = count(0.05) / count(0.1);
        assert!((ratio - 4.0).abs() < 0.5, "{ratio}");
        assert_eq!(count(0.001), count(0.0001), "clamped by the limit");
    }
}
