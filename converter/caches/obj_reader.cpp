#include "caches/obj_reader.h"

#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <unordered_map>

namespace segmorph {
namespace {

bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r';
}

Status read_text(const std::string& path, std::string& text) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return Status(StatusCode::io_error, path + ": cannot open: " + std::strerror(errno));
  std::ostringstream contents;
  contents << file.rdbuf();
  if (file.bad()) return Status(StatusCode::io_error, path + ": cannot read");
  text = contents.str();
  return Status::Ok();
}

// One pass over an OBJ's lines. A first frame (`first` null) collects everything ObjMesh holds; a later frame of a
// sequence collects its points and compares its faces with the first frame's.
class ObjParser {
 public:
  ObjParser(const std::string& path, const ObjMesh* first) : path_(path), first_(first) {}

  Status parse(const std::string& text, ObjMesh& mesh);

 private:
  Status fail(const std::string& what) const {
    return Status(StatusCode::bad_data, path_ + " line " + std::to_string(line_) + ": " + what);
  }
  Status read_floats(const char*& p, const char* end, int count, std::vector<float>& out);
  Status read_face(const char* p, const char* end, ObjMesh& mesh);
  Status read_index(const char*& p, const char* end, size_t count, const char* what, int64_t& index);
  Status finish(ObjMesh& mesh);

  std::string path_;
  const ObjMesh* first_;
  size_t line_ = 0;
  size_t texcoord_count_ = 0, normal_count_ = 0;
  std::vector<float> texcoords_, normals_;                // the vt and vn lines (first frame)
  std::vector<int64_t> corner_texcoord_, corner_normal_;  // per corner, -1 when it names none (first frame)
  size_t faces_ = 0, corners_ = 0;                        // read so far (later frames: compared so far)
};

Status ObjParser::read_floats(const char*& p, const char* end, int count, std::vector<float>& out) {
  for (int i = 0; i < count; ++i) {
    while (p < end && is_blank(*p)) ++p;
    if (p < end && *p == '+') ++p;
    float value = 0;
    const std::from_chars_result result = std::from_chars(p, end, value);
    if (result.ec != std::errc() || !std::isfinite(value))
      return fail("expected " + std::to_string(count) + " finite numbers");
    p = result.ptr;
    out.push_back(value);
  }
  return Status::Ok();
}

// A 1-based or negative index into `count` elements read so far, made 0-based. Absolute indices are checked against
// the file's final counts in finish() (a face may name a later v line).
Status ObjParser::read_index(const char*& p, const char* end, size_t count, const char* what, int64_t& index) {
  int64_t value = 0;
  const std::from_chars_result result = std::from_chars(p, end, value);
  if (result.ec != std::errc() || value == 0) return fail(std::string("a face has a bad ") + what + " index");
  p = result.ptr;
  if (value < 0 && uint64_t(-value) > count)
    return fail(std::string("a face's relative ") + what + " index " + std::to_string(value) + " is before the first");
  index = value > 0 ? value - 1 : int64_t(count) + value;
  return Status::Ok();
}

Status ObjParser::read_face(const char* p, const char* end, ObjMesh& mesh) {
  if (first_ && faces_ == first_->face_sizes.size())
    return fail("more faces than the first frame's " + std::to_string(faces_));
  const size_t point_count = mesh.points.size() / 3;
  uint32_t size = 0;
  while (true) {
    while (p < end && is_blank(*p)) ++p;
    if (p == end) break;
    int64_t point = -1, texcoord = -1, normal = -1;
    SEGMORPH_RETURN_IF_ERROR(read_index(p, end, point_count, "vertex", point));
    if (p < end && *p == '/') {
      ++p;
      if (p < end && *p != '/') SEGMORPH_RETURN_IF_ERROR(read_index(p, end, texcoord_count_, "texture", texcoord));
      if (p < end && *p == '/') {
        ++p;
        SEGMORPH_RETURN_IF_ERROR(read_index(p, end, normal_count_, "normal", normal));
      }
    }
    if (p < end && !is_blank(*p)) return fail("a face corner is not v, v/vt, v//vn or v/vt/vn");
    if (point > int64_t(UINT32_MAX - 1)) return fail("a face's vertex index is too large");
    if (first_) {
      const size_t corner = corners_ + size;
      if (corner >= first_->face_points.size() || first_->face_points[corner] != uint32_t(point))
        return fail("face " + std::to_string(faces_ + 1) + " differs from the first frame's");
    } else {
      mesh.face_points.push_back(uint32_t(point));
      corner_texcoord_.push_back(texcoord);
      corner_normal_.push_back(normal);
    }
    ++size;
  }
  if (size < 3) return fail("a face has fewer than 3 corners");
  if (first_ && (faces_ >= first_->face_sizes.size() || first_->face_sizes[faces_] != size))
    return fail("face " + std::to_string(faces_ + 1) + " differs from the first frame's");
  if (!first_) mesh.face_sizes.push_back(size);
  ++faces_;
  corners_ += size;
  return Status::Ok();
}

Status ObjParser::parse(const std::string& text, ObjMesh& mesh) {
  const char* p = text.data();
  const char* const end = p + text.size();
  while (p < end) {
    ++line_;
    const char* line_end = static_cast<const char*>(std::memchr(p, '\n', size_t(end - p)));
    if (!line_end) line_end = end;
    while (p < line_end && is_blank(*p)) ++p;
    const char* keyword = p;
    while (p < line_end && !is_blank(*p)) ++p;
    const std::string_view word(keyword, size_t(p - keyword));
    if (word == "v") {
      SEGMORPH_RETURN_IF_ERROR(read_floats(p, line_end, 3, mesh.points));
    } else if (word == "vt" && !first_) {
      SEGMORPH_RETURN_IF_ERROR(read_floats(p, line_end, 2, texcoords_));
      texcoords_.back() = 1.0f - texcoords_.back();  // OBJ's v grows upwards, glTF's downwards
      ++texcoord_count_;
    } else if (word == "vn" && !first_) {
      SEGMORPH_RETURN_IF_ERROR(read_floats(p, line_end, 3, normals_));
      ++normal_count_;
    } else if (word == "f") {
      SEGMORPH_RETURN_IF_ERROR(read_face(p, line_end, mesh));
    }
    p = line_end + (line_end < end ? 1 : 0);
  }
  return finish(mesh);
}

Status ObjParser::finish(ObjMesh& mesh) {
  const size_t point_count = mesh.points.size() / 3;
  if (first_) {
    if (point_count != first_->points.size() / 3)
      return Status(StatusCode::bad_data, path_ + ": " + std::to_string(point_count) + " vertices, the first frame " +
                                              std::to_string(first_->points.size() / 3));
    if (faces_ != first_->face_sizes.size())
      return Status(StatusCode::bad_data, path_ + ": " + std::to_string(faces_) + " faces, the first frame " +
                                              std::to_string(first_->face_sizes.size()));
    return Status::Ok();
  }
  if (faces_ == 0) return Status(StatusCode::bad_data, path_ + ": no faces (a mesh needs triangles or polygons)");
  for (size_t c = 0; c < mesh.face_points.size(); ++c) {
    if (mesh.face_points[c] >= point_count || corner_texcoord_[c] >= int64_t(texcoord_count_) ||
        corner_normal_[c] >= int64_t(normal_count_))
      return Status(StatusCode::bad_data, path_ + ": a face index is out of range (" + std::to_string(point_count) +
                                              " vertices, " + std::to_string(texcoord_count_) +
                                              " texture coordinates, " + std::to_string(normal_count_) + " normals)");
  }
  bool all_texcoords = true, all_normals = true;
  for (size_t c = 0; c < mesh.face_points.size(); ++c) {
    all_texcoords = all_texcoords && corner_texcoord_[c] >= 0;
    all_normals = all_normals && corner_normal_[c] >= 0;
  }

  // glTF vertices: the distinct corners, in order of first use.
  struct Key {
    uint32_t point;
    int64_t texcoord, normal;
    bool operator==(const Key& other) const {
      return point == other.point && texcoord == other.texcoord && normal == other.normal;
    }
  };
  struct KeyHash {
    size_t operator()(const Key& key) const {
      return std::hash<uint64_t>()(uint64_t(key.point) * 0x9E3779B97F4A7C15ull ^ uint64_t(key.texcoord) * 31 ^
                                   uint64_t(key.normal) * 0x100000001B3ull);
    }
  };
  std::unordered_map<Key, uint32_t, KeyHash> vertex_of;
  std::vector<uint32_t> corner_vertex(mesh.face_points.size());
  for (size_t c = 0; c < mesh.face_points.size(); ++c) {
    const Key key{mesh.face_points[c], all_texcoords ? corner_texcoord_[c] : -1, all_normals ? corner_normal_[c] : -1};
    auto inserted = vertex_of.emplace(key, uint32_t(mesh.vertex_point.size()));
    if (inserted.second) {
      mesh.vertex_point.push_back(key.point);
      if (all_texcoords)
        for (int i = 0; i < 2; ++i) mesh.texcoords.push_back(texcoords_[size_t(key.texcoord) * 2 + size_t(i)]);
      if (all_normals)
        for (int i = 0; i < 3; ++i) mesh.normals.push_back(normals_[size_t(key.normal) * 3 + size_t(i)]);
    }
    corner_vertex[c] = inserted.first->second;
  }
  size_t corner = 0;
  for (uint32_t size : mesh.face_sizes) {
    for (uint32_t k = 1; k + 1 < size; ++k)
      mesh.triangles.insert(mesh.triangles.end(),
                            {corner_vertex[corner], corner_vertex[corner + k], corner_vertex[corner + k + 1]});
    corner += size;
  }
  return Status::Ok();
}

}  // namespace

Status read_obj(const std::string& path, ObjMesh& mesh) {
  mesh = ObjMesh();
  std::string text;
  SEGMORPH_RETURN_IF_ERROR(read_text(path, text));
  return ObjParser(path, nullptr).parse(text, mesh);
}

Status read_obj_frame(const std::string& path, const ObjMesh& first, std::vector<float>& points) {
  std::string text;
  SEGMORPH_RETURN_IF_ERROR(read_text(path, text));
  ObjMesh frame;
  frame.points.reserve(first.points.size());
  SEGMORPH_RETURN_IF_ERROR(ObjParser(path, &first).parse(text, frame));
  points = std::move(frame.points);
  return Status::Ok();
}

}  // namespace segmorph
