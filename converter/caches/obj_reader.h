// Wavefront OBJ meshes, as vertex caches bring them: the base mesh of a PC2 or MDD point cache, and the frames of an
// OBJ sequence (one file per frame, every file with the first one's faces).
//
// Read: v (x y z; a w or vertex colours after them are ignored), vt (u v; v is flipped for glTF: 1 - v), vn, and f
// with 1-based or negative (relative) indices in any of the forms v, v/vt, v//vn, v/vt/vn. Polygons are triangulated
// as fans from their first corner. o, g, s, usemtl, mtllib, l and p lines and comments are skipped (one mesh, no
// materials). glTF vertices are the distinct (v, vt, vn) corners in the order of first use; each keeps the index of
// its OBJ position, the point a cache moves it with.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "segmorph/status.h"

namespace segmorph {

struct ObjMesh {
  std::vector<float> points;  // P × 3: the v lines, in file order (a point cache's points)

  // Per glTF vertex (V): its point, and its texture coordinates (V × 2) and normal (V × 3) when every corner of
  // the file names one (else empty).
  std::vector<uint32_t> vertex_point;
  std::vector<float> texcoords, normals;
  std::vector<uint32_t> triangles;  // T × 3, into the glTF vertices

  // The faces as point indices, for comparing the frames of a sequence: the corner count of each face, and every
  // corner's point.
  std::vector<uint32_t> face_sizes, face_points;

  size_t vertex_count() const { return vertex_point.size(); }
};

// Reads the OBJ at `path`. Fails with one line naming the file and line on anything it cannot take: a number that
// is not finite, an index out of range, a face of fewer than 3 corners, no faces.
Status read_obj(const std::string& path, ObjMesh& mesh);

// Reads the points of a later frame of a sequence whose first frame is `first`, checking that the frame has as many
// points and the same faces (by point index; its texture coordinates and normals are not read). `points`: P × 3.
Status read_obj_frame(const std::string& path, const ObjMesh& first, std::vector<float>& points);

}  // namespace segmorph
