#include "caches/point_cache.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

namespace segmorph {
namespace {

constexpr char kPc2Magic[12] = {'P', 'O', 'I', 'N', 'T', 'C', 'A', 'C', 'H', 'E', '2', '\0'};
constexpr uint64_t kPc2HeaderBytes = 32, kMddHeaderBytes = 8;
// Counts beyond these are refused whatever the file's size (a frame of 2^28 points is 3 GB).
constexpr uint64_t kMaxPoints = uint64_t(1) << 28, kMaxFrames = uint64_t(1) << 24;

uint32_t little_u32(const unsigned char* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}
uint32_t big_u32(const unsigned char* p) {
  return uint32_t(p[3]) | uint32_t(p[2]) << 8 | uint32_t(p[1]) << 16 | uint32_t(p[0]) << 24;
}
float as_float(uint32_t bits) {
  float value;
  std::memcpy(&value, &bits, sizeof(value));
  return value;
}

}  // namespace

Status PointCacheReader::bad(const std::string& what) const { return Status(StatusCode::bad_data, what); }

Status PointCacheReader::open(const std::string& path) {
  path_ = path;
  file_ = std::ifstream(path, std::ios::binary);
  if (!file_) return Status(StatusCode::io_error, "cannot open: " + std::string(std::strerror(errno)));
  file_.seekg(0, std::ios::end);
  const uint64_t size = uint64_t(file_.tellg());
  file_.seekg(0);
  unsigned char header[kPc2HeaderBytes] = {};
  file_.read(reinterpret_cast<char*>(header), std::streamsize(std::min<uint64_t>(size, kPc2HeaderBytes)));
  uint64_t expected = 0;
  if (size >= kPc2HeaderBytes && std::memcmp(header, kPc2Magic, sizeof(kPc2Magic)) == 0) {
    format_ = Format::pc2;
    const uint32_t version = little_u32(header + 12), points = little_u32(header + 16);
    const uint32_t samples = little_u32(header + 28);
    start_ = as_float(little_u32(header + 20));
    rate_ = as_float(little_u32(header + 24));
    if (version != 1) return bad("PC2 version " + std::to_string(version) + " (only version 1 is defined)");
    if (points == 0 || points > kMaxPoints || samples == 0 || samples > kMaxFrames)
      return bad("PC2 header claims " + std::to_string(points) + " points and " + std::to_string(samples) + " samples");
    if (!std::isfinite(start_) || !(rate_ > 0) || !std::isfinite(rate_))
      return bad("PC2 header has a bad start frame or sample rate");
    points_ = points, frames_ = samples;
    data_offset_ = kPc2HeaderBytes;
  } else {
    format_ = Format::mdd;
    if (size < kMddHeaderBytes) return bad("neither a PC2 nor an MDD cache: " + std::to_string(size) + " bytes");
    const uint32_t frames = big_u32(header), points = big_u32(header + 4);
    if (points == 0 || points > kMaxPoints || frames == 0 || frames > kMaxFrames)
      return bad("not a PC2 cache, and as an MDD cache its header claims " + std::to_string(frames) + " frames and " +
                 std::to_string(points) + " points");
    points_ = points, frames_ = frames;
    data_offset_ = kMddHeaderBytes + 4 * uint64_t(frames);
  }
  expected = data_offset_ + uint64_t(frames_) * points_ * 12;
  const std::string kind = format_ == Format::pc2 ? "PC2" : "MDD";
  if (size != expected)
    return bad(kind + " cache of " + std::to_string(frames_) + " frames of " + std::to_string(points_) + " points is " +
               std::to_string(expected) + " bytes, the file " + std::to_string(size) +
               (size < expected ? " (truncated)" : ""));
  if (format_ == Format::mdd) {
    std::vector<unsigned char> raw(4 * frames_);
    file_.seekg(std::streamoff(kMddHeaderBytes));
    if (!file_.read(reinterpret_cast<char*>(raw.data()), std::streamsize(raw.size()))) return bad("MDD: cannot read");
    mdd_times_.resize(frames_);
    for (size_t f = 0; f < frames_; ++f) {
      mdd_times_[f] = as_float(big_u32(&raw[4 * f]));
      if (!std::isfinite(mdd_times_[f]) || (f > 0 && !(mdd_times_[f] > mdd_times_[f - 1])))
        return bad("MDD frame " + std::to_string(f) + "'s time is not finite and after the previous frame's");
    }
  }
  return Status::Ok();
}

std::vector<float> PointCacheReader::times(double fps) const {
  if (format_ == Format::mdd) return mdd_times_;
  std::vector<float> times(frames_);
  for (size_t f = 0; f < frames_; ++f) times[f] = float((double(start_) + double(f) * rate_) / fps);
  return times;
}

Status PointCacheReader::read_frame(size_t f, std::vector<float>& out) {
  if (f >= frames_) return Status(StatusCode::invalid_argument, "no frame " + std::to_string(f));
  std::vector<unsigned char> raw(points_ * 12);
  file_.clear();
  file_.seekg(std::streamoff(data_offset_ + uint64_t(f) * points_ * 12));
  if (!file_.read(reinterpret_cast<char*>(raw.data()), std::streamsize(raw.size())))
    return bad("frame " + std::to_string(f) + ": cannot read");
  out.resize(points_ * 3);
  const bool big = format_ == Format::mdd;
  for (size_t i = 0; i < out.size(); ++i) {
    out[i] = as_float(big ? big_u32(&raw[4 * i]) : little_u32(&raw[4 * i]));
    if (!std::isfinite(out[i]))
      return bad("frame " + std::to_string(f) + ", point " + std::to_string(i / 3) + ": not a finite position");
  }
  return Status::Ok();
}

}  // namespace segmorph
