// Welded topology: the connectivity geometry processing needs, independent of glTF's vertex splits.
//
// glTF splits a vertex wherever its normal or texture coordinate changes (seams), and some files are
// triangle soups with one vertex per corner (Fox.glb). Geometry processing wants one vertex per surface
// point. Vertices are welded when their whole trajectories are equal, bit for bit, over every frame of
// every clip: seam copies always move together, while points that only touch in the first frame
// (closed lips, a tear in cloth) stay apart because they separate later.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/frame_sequence.h"

namespace segmorph {

struct WeldedTopology {
  // V: welded vertex of each original vertex.
  std::vector<uint32_t> welded_index;
  // W: the first original vertex of each welded vertex (its representative, for reading positions).
  std::vector<uint32_t> representative;
  // T' × 3 welded vertex indices; triangles that collapse when welded (two equal corners) are dropped.
  std::vector<uint32_t> triangles;
  // W: connected component of each welded vertex, numbered in order of first appearance.
  std::vector<uint32_t> component;
  size_t component_count = 0;

  size_t welded_count() const { return representative.size(); }
};

// Edge adjacency of the welded vertices in compressed-row form: the neighbours of w are
// neighbour[offset[w] .. offset[w + 1]), sorted ascending. Symmetric: u is w's neighbour when w is u's.
struct VertexAdjacency {
  std::vector<uint32_t> offset;  // W + 1
  std::vector<uint32_t> neighbour;
};
VertexAdjacency vertex_adjacency(const WeldedTopology& topology);

// The topology of a given welding: welded_index (V) numbers the welded vertices 0 .. welded_count − 1 in order of
// their first vertex (as weld_topology and a stream's welding do); triangles: T × 3 indices into V.
WeldedTopology welded_topology(std::vector<uint32_t> welded_index, size_t welded_count,
                               const std::vector<uint32_t>& triangles);

// Welds the vertices of one primitive over all of its clips. Every clip must have the same vertex
// count and triangles (they are samples of the same primitive); there must be at least one clip.
// Vertices no triangle uses are components of their own. With `also_equal` (V × 3 positions), vertices weld only
// where these are bit-identical too (+0 and −0 differ here): the encoder passes the decoder's base mesh, whose groups
// of identical positions the stream's welding refers to (a lossy base may separate vertices whose frames are equal).
WeldedTopology weld_topology(const std::vector<FrameSequence>& clips, const std::vector<float>* also_equal = nullptr);

}  // namespace segmorph
