//! Tangents for normal-mapped meshes that do not store them. glTF asks for MikkTSpace, the
//! frame normal maps are baked in (the `bevy_mikktspace` crate: a safe port of the reference
//! implementation).
//! MikkTSpace gives each triangle corner its tangent; the sample's vertices are shared by the
//! triangles around them, so the corners' tangents are averaged per vertex (the same where
//! the mesh's texture coordinates are continuous, as at every vertex off a UV seam).
use glam::{Vec3, Vec4};

struct Mesh<'a> {
    positions: &'a [Vec3],
    normals: &'a [Vec3],
    uvs: &'a [[f32; 2]],
    indices: &'a [u32],
    /// Per vertex: the sum of its corners' tangents, and the first corner's bitangent sign.
    sum: Vec<Vec3>,
    sign: Vec<f32>,
}

impl Mesh<'_> {
    fn vertex(&self, face: usize, vert: usize) -> usize {
        self.indices[face * 3 + vert] as usize
    }
}

impl bevy_mikktspace::Geometry for Mesh<'_> {
    fn num_faces(&self) -> usize {
        self.indices.len() / 3
    }
    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }
    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.positions[self.vertex(face, vert)].to_array()
    }
    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.normals[self.vertex(face, vert)].to_array()
    }
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        // glTF's v runs down the image, MikkTSpace's up (as OpenGL's): flipped, the signs
        // come out in glTF's convention (bitangent = cross(normal, tangent) x w).
        let [u, v] = self.uvs[self.vertex(face, vert)];
        [u, 1.0 - v]
    }
    fn set_tangent(&mut self, tangent_space: Option<bevy_mikktspace::TangentSpace>, face: usize, vert: usize) {
        let Some(tangent_space) = tangent_space else { return };
        let tangent = tangent_space.tangent_encoded();
        let v = self.vertex(face, vert);
        if self.sum[v] == Vec3::ZERO {
            self.sign[v] = tangent[3];
        }
        self.sum[v] += Vec3::new(tangent[0], tangent[1], tangent[2]);
    }
}

/// Per-vertex MikkTSpace tangents (xyz, bitangent sign), or none when the lists disagree in
/// length, an index is out of range, or MikkTSpace fails.
pub fn mikktspace(positions: &[Vec3], normals: &[Vec3], uvs: &[[f32; 2]], indices: &[u32]) -> Vec<Vec4> {
    let n = positions.len();
    if normals.len() != n || uvs.len() != n || indices.iter().any(|&i| i as usize >= n) || !indices.len().is_multiple_of(3) {
        return Vec::new();
    }
    let mut mesh = Mesh { positions, normals, uvs, indices, sum: vec![Vec3::ZERO; n], sign: vec![1.0; n] };
    if bevy_mikktspace::generate_tangents(&mut mesh).is_err() {
        return Vec::new();
    }
    // A vertex no triangle uses, or whose corners cancel, gets none (zero: the raster pass
    // then takes the frame from screen derivatives).
    mesh.sum.iter().zip(&mesh.sign).map(|(t, &s)| t.try_normalize().map_or(Vec4::ZERO, |t| t.extend(s))).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quad in the XY plane facing +Z, u along +X and v down its Y (glTF's image
    /// convention): every vertex's tangent is +X.
    #[test]
    fn a_quad_gets_the_tangent_along_u() {
        let positions = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::new(1.0, 1.0, 0.0)];
        let normals = [Vec3::Z; 4];
        let uvs = [[0.0, 1.0], [1.0, 1.0], [0.0, 0.0], [1.0, 0.0]];
        let t = mikktspace(&positions, &normals, &uvs, &[0, 1, 2, 2, 1, 3]);
        assert_eq!(t.len(), 4);
        for v in t {
            assert!((v.truncate() - Vec3::X).length() < 1e-5 && v.w.abs() == 1.0, "{v}");
        }
    }
}
