// Point caches, read frame by frame: PC2 (Blender's and 3ds Max's "POINTCACHE2") and MDD (LightWave's, written by
// Blender's io_shape_mdd). Each holds, per frame, the position of every point of a mesh whose topology lives
// elsewhere (an OBJ or a glTF base mesh, in the exporter's vertex order).
//
//   PC2, little-endian: "POINTCACHE2\0", int32 version (1), int32 points, float32 start frame, float32 sample rate
//        (frames between samples), int32 samples; then samples x points x 3 float32.
//   MDD, big-endian: int32 frames, int32 points, frames x float32 time (seconds); then frames x points x 3 float32.
//
// The header is checked against the file's size before anything is allocated; every position read is finite.
#pragma once

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "segmorph/status.h"

namespace segmorph {

class PointCacheReader {
 public:
  enum class Format { pc2, mdd };

  // Reads and checks the header of `path` (PC2 when it starts with POINTCACHE2, MDD otherwise).
  Status open(const std::string& path);

  Format format() const { return format_; }
  size_t point_count() const { return points_; }
  size_t frame_count() const { return frames_; }
  const std::string& path() const { return path_; }
  // PC2's header: the first sample's frame number, and frames between samples.
  float pc2_start() const { return start_; }
  float pc2_rate() const { return rate_; }
  // Each frame's time in seconds: MDD's own; PC2's frame number (start + f x rate) divided by `fps`.
  std::vector<float> times(double fps) const;

  // Frame `f`'s positions, point_count x 3 floats, into `out` (resized).
  Status read_frame(size_t f, std::vector<float>& out);

 private:
  Status bad(const std::string& what) const;

  std::string path_;
  std::ifstream file_;
  Format format_ = Format::pc2;
  size_t points_ = 0, frames_ = 0;
  uint64_t data_offset_ = 0;
  float start_ = 0, rate_ = 1;  // PC2
  std::vector<float> mdd_times_;
};

}  // namespace segmorph
