#include "draco_base_mesh.h"

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <queue>
#include <unordered_map>

namespace segmorph {
namespace {

draco::GeometryAttribute::Type draco_type(const std::string& semantic) {
  if (semantic == "POSITION") return draco::GeometryAttribute::POSITION;
  if (semantic == "NORMAL") return draco::GeometryAttribute::NORMAL;
  if (semantic.rfind("TEXCOORD_", 0) == 0) return draco::GeometryAttribute::TEX_COORD;
  if (semantic.rfind("COLOR_", 0) == 0) return draco::GeometryAttribute::COLOR;
  return draco::GeometryAttribute::GENERIC;
}

int add_float_attribute(draco::Mesh& mesh, const BaseMeshAttribute& attribute) {
  draco::GeometryAttribute geometry;
  geometry.Init(draco_type(attribute.semantic), nullptr, int8_t(attribute.components), draco::DT_FLOAT32, false,
                int64_t(sizeof(float)) * attribute.components, 0);
  const size_t count = attribute.values.size() / size_t(attribute.components);
  const int id = mesh.AddAttribute(geometry, true, uint32_t(count));
  draco::PointAttribute* point_attribute = mesh.attribute(id);
  for (size_t v = 0; v < count; ++v)
    point_attribute->SetAttributeValue(draco::AttributeValueIndex(uint32_t(v)),
                                       &attribute.values[v * size_t(attribute.components)]);
  return id;
}

// An integer attribute, which Draco codes exactly (its quantization is for floats); -1 when a value is not an
// integer of type T.
template <typename T>
int add_integer_attribute(draco::Mesh& mesh, const BaseMeshAttribute& attribute) {
  for (float value : attribute.values)
    if (!(value >= 0 && value <= float(std::numeric_limits<T>::max()) && value == std::floor(value))) return -1;
  draco::GeometryAttribute geometry;
  geometry.Init(draco::GeometryAttribute::GENERIC, nullptr, int8_t(attribute.components),
                sizeof(T) == 1 ? draco::DT_UINT8 : draco::DT_UINT16, attribute.normalized,
                int64_t(sizeof(T)) * attribute.components, 0);
  const size_t count = attribute.values.size() / size_t(attribute.components);
  const int id = mesh.AddAttribute(geometry, true, uint32_t(count));
  draco::PointAttribute* point_attribute = mesh.attribute(id);
  T element[4];
  for (size_t v = 0; v < count; ++v) {
    for (int c = 0; c < attribute.components; ++c) element[c] = T(attribute.values[v * size_t(attribute.components) + size_t(c)]);
    point_attribute->SetAttributeValue(draco::AttributeValueIndex(uint32_t(v)), element);
  }
  return id;
}

}  // namespace

Status encode_draco_base_mesh(const BaseMesh& mesh, const DracoSettings& settings, std::vector<uint8_t>& bytes,
                              std::map<std::string, int>& attribute_ids) {
  draco::Mesh draco_mesh;
  draco_mesh.set_num_points(uint32_t(mesh.vertex_count));
  attribute_ids.clear();
  for (const BaseMeshAttribute& attribute : mesh.attributes) {
    if (attribute.components < 1 || attribute.components > 4 ||
        attribute.values.size() != mesh.vertex_count * size_t(attribute.components))
      return Status(StatusCode::invalid_argument, "base mesh attribute " + attribute.semantic + " has the wrong size");
    const int id = attribute.type == AttributeType::float32 ? add_float_attribute(draco_mesh, attribute)
                   : attribute.type == AttributeType::uint8  ? add_integer_attribute<uint8_t>(draco_mesh, attribute)
                                                             : add_integer_attribute<uint16_t>(draco_mesh, attribute);
    if (id < 0)
      return Status(StatusCode::invalid_argument, "base mesh attribute " + attribute.semantic + " holds a value its type cannot");
    attribute_ids[attribute.semantic] = int(draco_mesh.attribute(id)->unique_id());
  }
  draco_mesh.SetNumFaces(mesh.triangles.size() / 3);
  for (size_t t = 0; t < mesh.triangles.size() / 3; ++t) {
    draco::Mesh::Face face;
    for (int c = 0; c < 3; ++c) {
      if (mesh.triangles[t * 3 + size_t(c)] >= mesh.vertex_count)
        return Status(StatusCode::invalid_argument, "base mesh triangle names a missing vertex");
      face[c] = draco::PointIndex(mesh.triangles[t * 3 + size_t(c)]);
    }
    draco_mesh.SetFace(draco::FaceIndex(uint32_t(t)), face);
  }

  if (settings.share_values) {
    // Sharing values maps points to values through a table that only the mesh's own (not the attributes')
    // deduplication keeps consistent; points equal in every value become one.
    if (!draco_mesh.DeduplicateAttributeValues())
      return Status(StatusCode::numerical, "Draco could not share the base mesh's attribute values");
    draco_mesh.DeduplicatePointIds();
  }
  draco::Encoder encoder;
  encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, settings.position_bits);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, settings.normal_bits);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::TEX_COORD, settings.texcoord_bits);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::COLOR, settings.color_bits);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::GENERIC, settings.generic_bits);
  encoder.SetSpeedOptions(settings.speed, settings.speed);
  encoder.SetEncodingMethod(settings.keep_order ? draco::MESH_SEQUENTIAL_ENCODING : draco::MESH_EDGEBREAKER_ENCODING);
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeMeshToBuffer(draco_mesh, &buffer);
  if (!status.ok()) return Status(StatusCode::numerical, "Draco could not encode the base mesh: " + status.error_msg_string());
  bytes.assign(buffer.data(), buffer.data() + buffer.size());
  return Status::Ok();
}

Status decode_draco_base_mesh(const uint8_t* data, size_t size, const std::map<std::string, int>& attribute_ids,
                              BaseMesh& mesh, size_t max_vertices) {
  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(data), size);
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  if (!decoded.ok()) return Status(StatusCode::bad_data, "Draco cannot decode the base mesh: " + decoded.status().error_msg_string());
  const std::unique_ptr<draco::Mesh> draco_mesh = std::move(decoded).value();
  if (draco_mesh->num_points() > max_vertices || draco_mesh->num_faces() > 4 * max_vertices)
    return Status(StatusCode::bad_data, "the Draco base mesh is absurdly large");
  mesh = BaseMesh();
  mesh.vertex_count = draco_mesh->num_points();
  for (const auto& [semantic, id] : attribute_ids) {
    const draco::PointAttribute* attribute = draco_mesh->GetAttributeByUniqueId(uint32_t(id));
    if (!attribute) return Status(StatusCode::bad_data, "the Draco base mesh has no attribute " + std::to_string(id) + " for " + semantic);
    BaseMeshAttribute out;
    out.semantic = semantic;
    out.components = attribute->num_components();
    if (out.components < 1 || out.components > 4) return Status(StatusCode::bad_data, "Draco attribute " + semantic + " has a bad size");
    out.values.resize(mesh.vertex_count * size_t(out.components));
    // Unsigned integers of 8 and 16 bits are read as they are (their integers); every other type as floats.
    const draco::DataType data_type = attribute->data_type();
    if (data_type == draco::DT_UINT8 || data_type == draco::DT_UINT16) {
      out.type = data_type == draco::DT_UINT8 ? AttributeType::uint8 : AttributeType::uint16;
      out.normalized = attribute->normalized();
      uint16_t element[4];
      for (uint32_t v = 0; v < mesh.vertex_count; ++v) {
        if (!attribute->ConvertValue<uint16_t>(attribute->mapped_index(draco::PointIndex(v)), int8_t(out.components),
                                               element))
          return Status(StatusCode::bad_data, "Draco attribute " + semantic + " cannot be read as integers");
        for (int c = 0; c < out.components; ++c) out.values[size_t(v) * size_t(out.components) + size_t(c)] = element[c];
      }
    } else {
      for (uint32_t v = 0; v < mesh.vertex_count; ++v)
        if (!attribute->ConvertValue<float>(attribute->mapped_index(draco::PointIndex(v)), int8_t(out.components),
                                            &out.values[size_t(v) * size_t(out.components)]))
          return Status(StatusCode::bad_data, "Draco attribute " + semantic + " cannot be read as floats");
    }
    if (semantic == "POSITION") mesh.attributes.insert(mesh.attributes.begin(), std::move(out));
    else mesh.attributes.push_back(std::move(out));
  }
  mesh.triangles.resize(size_t(draco_mesh->num_faces()) * 3);
  for (uint32_t t = 0; t < draco_mesh->num_faces(); ++t)
    for (int c = 0; c < 3; ++c) {
      // Draco does not check this itself: a corrupt stream can name points that do not exist.
      const uint32_t index = draco_mesh->face(draco::FaceIndex(t))[c].value();
      if (index >= mesh.vertex_count) return Status(StatusCode::bad_data, "the Draco base mesh has a triangle naming a missing vertex");
      mesh.triangles[size_t(t) * 3 + size_t(c)] = index;
    }
  return Status::Ok();
}

// At most kMaxCandidates originals within the search radius are considered for each decoded vertex (see
// match_decoded_vertices), the cheapest of at most kMaxScanned found there: where thousands of originals share a
// step (a dense part, a part collapsed to a point), nearness cannot choose among them anyway, and scanning them all
// for every vertex would take time quadratic in their number.
constexpr size_t kMaxCandidates = 16, kMaxScanned = 1024;

namespace {

// The search behind match_decoded_vertices: a grid of the originals' positions in cells of the search radius, the
// cost of a pairing, the candidates of a decoded vertex, and the triangle-by-triangle matching, surest first.
class VertexMatcher {
 public:
  VertexMatcher(const BaseMesh& original, const BaseMesh& decoded, const DracoSettings& settings);
  Status match(std::vector<uint32_t>& source);

 private:
  struct Fit {
    double score = INFINITY, sureness = 0;
    uint32_t triangle = 0, corners[3] = {0, 0, 0};
  };
  // Cell coordinates hashed in unsigned arithmetic, and 0 for a cell beyond ±2^62 (or NaN): no overflow for any
  // float.
  int64_t cell(const float* p, int c) const {
    const double q = std::floor(double(p[c]) / radius_);
    return q >= -0x1p62 && q <= 0x1p62 ? int64_t(q) : int64_t(0);
  }
  static uint64_t key(int64_t x, int64_t y, int64_t z) {
    return uint64_t(x) * 73856093u ^ uint64_t(y) * 19349663u ^ uint64_t(z) * 83492791u;
  }
  double cost(uint32_t p, uint32_t v) const;
  std::vector<uint32_t> candidates(uint32_t p) const;
  Fit best_fit(uint32_t d, const std::vector<uint32_t>& source) const;
  void match_triangles(std::vector<uint32_t>& source);
  Status match_leftovers(std::vector<uint32_t>& source) const;

  const BaseMesh& original_;
  const BaseMesh& decoded_;
  const std::vector<float>& positions_;
  const std::vector<float>& decoded_positions_;
  double step_ = 1;    // Draco's quantization step; costs are in steps
  double radius_ = 1;  // how far a decoded position can be from its original: the search radius and the grid's cell
  std::unordered_multimap<uint64_t, uint32_t> grid_;
  // Other attributes, by semantic, to tell apart vertices that share a position (seams).
  std::vector<std::pair<const BaseMeshAttribute*, const BaseMeshAttribute*>> others_;
  std::vector<std::vector<uint32_t>> incident_, decoded_incident_, corner_candidates_;
  std::vector<bool> taken_;
};

VertexMatcher::VertexMatcher(const BaseMesh& original, const BaseMesh& decoded, const DracoSettings& settings)
    : original_(original),
      decoded_(decoded),
      positions_(original.attributes[0].values),
      decoded_positions_(decoded.attributes[0].values) {
  double extent = 0, magnitude = 0;
  for (int c = 0; c < 3; ++c) {
    double low = INFINITY, high = -INFINITY;
    for (size_t v = 0; v < original.vertex_count; ++v) {
      low = std::min(low, double(positions_[v * 3 + size_t(c)]));
      high = std::max(high, double(positions_[v * 3 + size_t(c)]));
    }
    if (original.vertex_count) {
      extent = std::max(extent, high - low);
      magnitude = std::max({magnitude, std::fabs(low), std::fabs(high)});
    }
  }
  // Draco's positions are within half a step per axis of the originals, plus the rounding of its float arithmetic
  // (it quantizes and dequantizes in floats: a few units in the last place of the largest coordinate). At 21-22 bits
  // such a unit is a quarter of a step or more for a mesh that lies away from the origin: measured, decoded vertices of
  // AnimatedMorphSphere, RobotExpressive (22 bits) and CesiumMan (21) lay 1.16, 1.01 and 1.005 steps from their
  // originals, beyond a radius of one step. The radius is one step or, when larger, the bound on the distance: half
  // a step and four units in the last place per axis. A mesh of one point (extent 0) is one cell of any size.
  step_ = extent > 0 ? extent / double((1 << settings.position_bits) - 1) : 1.0;
  const double unit_in_last_place = magnitude * std::numeric_limits<float>::epsilon();
  radius_ = std::max(step_, std::sqrt(3.0) * (step_ / 2 + 4 * unit_in_last_place));
  grid_.reserve(original.vertex_count);
  for (uint32_t v = 0; v < original.vertex_count; ++v)
    grid_.emplace(key(cell(&positions_[size_t(v) * 3], 0), cell(&positions_[size_t(v) * 3], 1),
                      cell(&positions_[size_t(v) * 3], 2)),
                  v);
  for (size_t a = 1; a < decoded.attributes.size(); ++a)
    for (size_t b = 1; b < original.attributes.size(); ++b)
      if (original.attributes[b].semantic == decoded.attributes[a].semantic &&
          original.attributes[b].components == decoded.attributes[a].components)
        others_.push_back({&original.attributes[b], &decoded.attributes[a]});
}

// How unlike original vertex v decoded vertex p is; infinite beyond the search radius.
double VertexMatcher::cost(uint32_t p, uint32_t v) const {
  const float* q = &decoded_positions_[size_t(p) * 3];
  double distance = 0;
  for (int c = 0; c < 3; ++c) distance += std::pow(double(q[c]) - positions_[size_t(v) * 3 + size_t(c)], 2);
  if (distance > radius_ * radius_) return double(INFINITY);
  double total = distance / (step_ * step_);
  for (const auto& [from, to] : others_)
    for (int c = 0; c < from->components; ++c)
      total += std::pow(double(to->values[size_t(p) * size_t(to->components) + size_t(c)]) -
                            from->values[size_t(v) * size_t(from->components) + size_t(c)],
                        2);
  return total;
}

// The originals within the search radius of decoded vertex p, in increasing index order.
std::vector<uint32_t> VertexMatcher::candidates(uint32_t p) const {
  const float* q = &decoded_positions_[size_t(p) * 3];
  std::vector<uint32_t> found;
  for (int64_t dx = -1; dx <= 1; ++dx)
    for (int64_t dy = -1; dy <= 1; ++dy)
      for (int64_t dz = -1; dz <= 1; ++dz) {
        const auto range = grid_.equal_range(key(cell(q, 0) + dx, cell(q, 1) + dy, cell(q, 2) + dz));
        for (auto it = range.first; it != range.second && found.size() < kMaxScanned; ++it)
          if (cost(p, it->second) < INFINITY) found.push_back(it->second);
      }
  std::sort(found.begin(), found.end());
  found.erase(std::unique(found.begin(), found.end()), found.end());
  // Thousands of originals can lie within the radius (a dense part, a part collapsed to a point): the cheapest few
  // bound the matching's work (equally cheap ones by index).
  if (found.size() > kMaxCandidates) {
    std::stable_sort(found.begin(), found.end(), [&](uint32_t a, uint32_t b) { return cost(p, a) < cost(p, b); });
    found.resize(kMaxCandidates);
  }
  return found;
}

// The original triangle that fits decoded triangle d best, with its corners, and how much better than the next.
VertexMatcher::Fit VertexMatcher::best_fit(uint32_t d, const std::vector<uint32_t>& source) const {
  constexpr double kTaken = 1e12, kDisagrees = 1e6;
  const uint32_t* corner = &decoded_.triangles[size_t(d) * 3];
  Fit best;
  double second = INFINITY;
  // The original triangles around the candidates of one corner: the corner with the fewest such triangles.
  int pivot = 0;
  size_t fewest = SIZE_MAX;
  for (int k = 0; k < 3; ++k) {
    size_t around = 0;
    for (uint32_t candidate : corner_candidates_[corner[k]]) around += incident_[candidate].size();
    if (around < fewest) fewest = around, pivot = k;
  }
  for (uint32_t candidate : corner_candidates_[corner[pivot]])
    for (uint32_t t : incident_[candidate])
      for (int c = 0; c < 3; ++c) {
        const uint32_t* o = &original_.triangles[size_t(t) * 3];
        if (o[c] != candidate) continue;
        uint32_t v[3];  // the original of each corner under this match
        for (int j = 0; j < 3; ++j) v[(pivot + j) % 3] = o[(c + j) % 3];
        double score = taken_[t] ? kTaken : 0.0;
        for (int k = 0; k < 3; ++k) {
          score += cost(corner[k], v[k]);
          if (source[corner[k]] != UINT32_MAX && source[corner[k]] != v[k]) score += kDisagrees;
        }
        if (score < best.score) {
          second = best.score;
          best.score = score, best.triangle = t, best.corners[0] = v[0], best.corners[1] = v[1], best.corners[2] = v[2];
        } else if (score < second) {
          second = score;
        }
      }
  best.sureness = second == INFINITY ? INFINITY : second - best.score;
  return best;
}

// Draco keeps every triangle (it renumbers vertices and reorders triangles and their corners). Each decoded triangle
// is matched to an original triangle whose corners are near its own, and its corners come from that triangle's.
// Nearness alone is not enough: vertices of different parts can lie within a step of each other, alike in every
// attribute (measured: 78 triangles of the chicken and 8 of the horse came out joining vertices of different
// triangles when each vertex took its nearest original), and such a vertex would follow the wrong part's trajectory.
// So triangles are matched surest first, the sureness of a triangle being how much better its best original
// triangle fits than the next one, where a fit counts nearness and, far above it, whether the original triangle is
// still free and whether it agrees with the corners already matched; each match makes its neighbours' choices surer,
// so matches grow over each part from its least ambiguous triangles.
void VertexMatcher::match_triangles(std::vector<uint32_t>& source) {
  incident_.assign(original_.vertex_count, {});
  decoded_incident_.assign(decoded_.vertex_count, {});
  for (size_t t = 0; t < original_.triangles.size() / 3; ++t)
    for (int c = 0; c < 3; ++c) incident_[original_.triangles[t * 3 + size_t(c)]].push_back(uint32_t(t));
  const size_t decoded_triangles = decoded_.triangles.size() / 3;
  for (size_t d = 0; d < decoded_triangles; ++d)
    for (int c = 0; c < 3; ++c) decoded_incident_[decoded_.triangles[d * 3 + size_t(c)]].push_back(uint32_t(d));
  corner_candidates_.assign(decoded_.vertex_count, {});
  for (uint32_t p = 0; p < decoded_.vertex_count; ++p)
    if (!decoded_incident_[p].empty()) corner_candidates_[p] = candidates(p);
  taken_.assign(original_.triangles.size() / 3, false);
  std::vector<bool> matched(decoded_triangles, false);
  // Surest first; equally sure ones in decoded order.
  std::priority_queue<std::pair<double, int64_t>> queue;
  for (size_t d = 0; d < decoded_triangles; ++d) queue.push({best_fit(uint32_t(d), source).sureness, -int64_t(d)});
  while (!queue.empty()) {
    const auto [sureness, negative_d] = queue.top();
    queue.pop();
    const uint32_t d = uint32_t(-negative_d);
    if (matched[d]) continue;
    const Fit fit = best_fit(d, source);
    if (fit.sureness != sureness) {  // its neighbourhood changed since it was queued
      queue.push({fit.sureness, negative_d});
      continue;
    }
    matched[d] = true;
    if (fit.score == INFINITY) continue;  // no original triangle fits: its corners fall back on nearness
    taken_[fit.triangle] = true;
    const uint32_t* corner = &decoded_.triangles[size_t(d) * 3];
    for (int k = 0; k < 3; ++k) {
      if (source[corner[k]] != UINT32_MAX) continue;
      source[corner[k]] = fit.corners[k];
      for (uint32_t neighbour : decoded_incident_[corner[k]])
        if (!matched[neighbour]) queue.push({best_fit(neighbour, source).sureness, -int64_t(neighbour)});
    }
  }
}

// Vertices no matched triangle names (unused by triangles, or in a triangle Draco changed): the nearest original,
// preferring those no decoded vertex came from yet, so that duplicates map one to one where Draco kept them apart.
Status VertexMatcher::match_leftovers(std::vector<uint32_t>& source) const {
  std::vector<bool> claimed(original_.vertex_count, false);
  for (uint32_t p = 0; p < decoded_.vertex_count; ++p)
    if (source[p] != UINT32_MAX) claimed[source[p]] = true;
  for (uint32_t p = 0; p < decoded_.vertex_count; ++p) {
    if (source[p] != UINT32_MAX) continue;
    double best_cost = INFINITY;
    uint32_t best = UINT32_MAX;
    for (uint32_t v : candidates(p)) {
      const double total = cost(p, v) + (claimed[v] ? 1e6 : 0.0);
      if (total < best_cost) best_cost = total, best = v;
    }
    if (best == UINT32_MAX)
      return Status(StatusCode::numerical, "a vertex Draco decoded matches no vertex of the base mesh");
    source[p] = best;
    claimed[best] = true;
  }
  return Status::Ok();
}

Status VertexMatcher::match(std::vector<uint32_t>& source) {
  source.assign(decoded_.vertex_count, UINT32_MAX);
  match_triangles(source);
  return match_leftovers(source);
}

}  // namespace

Status match_decoded_vertices(const BaseMesh& original, const BaseMesh& decoded, const DracoSettings& settings,
                              std::vector<uint32_t>& source) {
  VertexMatcher matcher(original, decoded, settings);
  return matcher.match(source);
}

}  // namespace segmorph
