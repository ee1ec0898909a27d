// segmorph's pipeline API: whole glTF files through info, bake, encode, decode and verify, as the segmorph tool runs
// them (the tool is argument parsing and printing over these functions). For asset pipelines written in C++: an
// engine's importer, a DCC exporter, a build tool. Link segmorph::segmorph (find_package(segmorph CONFIG)); tinygltf,
// Draco, Eigen and Spectra are inside, none of them in this header. docs/library.md has a worked example.
//
// Errors come back as a Status (include/segmorph/status.h), never as an exception or a print (a failed allocation is
// OUT_OF_MEMORY; tests/out_of_memory_test.cpp fails allocations throughout info, bake, encode, decode and verify; an
// allocation that fails inside tinygltf's JSON parser, in Model::load, may end the process: tinygltf 2.7 lets it
// reach a noexcept function there). Progress on long work, when the caller asks for it, as calls of a function it
// gives. Units: KG error in percent, rates in bits per vertex per frame of the whole file, times in seconds, sizes in
// bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "segmorph/encoding.h"  // RateMode, StreamReport
#include "segmorph/status.h"
#include "segmorph/version.h"

namespace segmorph {

// One line of progress on long work ("encoding mesh 1 primitive 0 (2904 vertices)"); empty: no progress.
using Progress = std::function<void(const std::string& message)>;

struct CacheSource;
struct CacheReport;

// A glTF 2.0 asset in memory: what load() read, what the functions below transform.
class Model {
 public:
  Model();
  ~Model();
  Model(const Model& other);
  Model& operator=(const Model& other);
  Model(Model&& other) noexcept;
  Model& operator=(Model&& other) noexcept;

  // Reads a .glb or a .gltf (its buffers and images resolved beside it). `warnings` receives what the loader let
  // pass. Fails on anything that is not valid enough to process, with a one-line message.
  static Status load(const std::string& path, Model& model, std::vector<std::string>* warnings = nullptr);

  // Reads a vertex cache (docs/caches.md) as the glTF bake would write for it: the base mesh with one morph target
  // per frame, played by a one-hot weights animation named after the cache. `report` says what was read and how to
  // sample the model so that every frame is kept. Fails on any bad input with one line naming the file (and frame).
  static Status load_cache(const CacheSource& source, Model& model, CacheReport* report = nullptr,
                           const Progress& progress = {});

  // Writes `path`: binary if it ends in .glb, JSON with a .bin beside it if it ends in .gltf, whole or not at all.
  // The file holds one buffer; what nothing refers to is dropped from the model first (the model changes
  // accordingly), and the buffer's bytes are written from where they are, without a copy of them.
  Status save(const std::string& path);

  // The bytes save() would write as a .glb (images that are files included as it embeds them).
  size_t glb_size() const;

  // The implementation's model (tinygltf's), for segmorph's own code.
  struct Data;
  Data& data() { return *data_; }
  const Data& data() const { return *data_; }

 private:
  std::unique_ptr<Data> data_;
};

// Bytes of the file at `path` and of the files its buffers and images name (a .gltf's .bin): what a server sends.
size_t file_bytes(const std::string& path, const Model& model);

// True when saving to `output` would write over `input_path` or a file the model loaded from it reads (a .gltf's
// .bin, its images), through links too: the save would replace its own source.
bool writes_over(const std::string& output, const std::string& input_path, const Model& input);

// How animation is sampled into frames (docs/baking.md).
struct SampleSettings {
  // Frames per second of a regular grid; 0 selects the default: the union of the clip's key times when there are at
  // most kMaxKeyRate of them per second, else a regular kDefaultFps grid.
  double fps = 0;
  static constexpr double kMaxKeyRate = 60;
  static constexpr double kDefaultFps = 30;
  // The most frames a regular grid may give one clip (over 9 hours at 30 fps): a clip whose keys span longer at
  // `fps` is refused rather than sampled into frames no memory holds.
  static constexpr double kMaxGridFrames = 1e6;
};

// A vertex cache, read by Model::load_cache.
struct CacheSource {
  // An OBJ sequence: a folder of .obj files, one per frame, ordered by the number in their names, or a printf
  // pattern such as frames/walk_%04d.obj; the numbers must be consecutive. With `cache`: the base mesh the cache
  // moves, an .obj (the cache's points are its v lines) or a .glb or .gltf of one mesh (its vertices, primitive after
  // primitive), unanimated.
  std::string mesh;
  std::string cache;  // a PC2 or MDD point cache; empty for an OBJ sequence
  // Frames per second of an OBJ sequence and of a PC2 cache's frame numbers (an MDD cache has its own times).
  double fps = 30;
  // The cache and an OBJ mesh are Z up (Blender's own axes, which its MDD exporter always writes): turned to glTF's
  // Y up, (x, y, z) -> (x, z, -y). A glTF base mesh is Y up already and stays as it is.
  bool z_up = false;
};

struct CacheReport {
  std::string format;  // "OBJ sequence", "PC2" or "MDD"
  bool own_times = false;  // the cache gives each frame's time (MDD), rather than a number at CacheSource::fps
  size_t points = 0;   // the cache's points (the OBJ's v lines)
  size_t vertices = 0, frames = 0;  // of the glTF primitive(s) it became
  double first_time = 0, last_time = 0;  // seconds
  // Sampling that keeps every frame: at the keys (fps 0) up to SampleSettings::kMaxKeyRate frames per second, at
  // the cache's own rate above that.
  SampleSettings sampling;
};

// --- inputs ---

// One input of a command as a user names it: a glTF file (.glb or .gltf; "-": the standard input), an OBJ sequence
// (a folder, or a printf pattern with a % that is not a glTF's name), or a base mesh with its point cache.
struct Input {
  std::string path;
  std::string cache;   // a PC2 or MDD point cache that moves `path` (an .obj, .glb or .gltf); empty otherwise
  bool z_up = false;   // CacheSource::z_up
  bool caches = true;  // false: `path` is read as a glTF whatever its name (decode reads nothing else)
};

enum class InputKind { gltf, obj_sequence, point_cache };
InputKind input_kind(const Input& input);

// Reads `input` into `model` (a glTF with Model::load, a vertex cache with Model::load_cache) and gives in `sampling`
// how to sample it: `requested` for a glTF (whose fps is also an OBJ sequence's and a PC2 cache's frame rate, as
// CacheSource::fps), a cache's own frames (CacheReport::sampling) for a vertex cache, unless an MDD cache is resampled
// at a requested fps. Refuses an .obj alone and a point cache given as the input, saying what to give instead (unless
// input.caches is false). Progress: what it reads, the loader's warnings, what a cache held. `cache`, when given,
// receives a vertex cache's report.
Status load_input(const Input& input, const SampleSettings& requested, Model& model, SampleSettings& sampling,
                  const Progress& progress = {}, CacheReport* cache = nullptr);

// The bytes of `input` as a server sends them: its files (a glTF's with its .bin and images; a point cache and its
// mesh); for an OBJ sequence or the standard input, those of the glTF it reads as (`model`, as a .glb).
size_t input_bytes(const Input& input, const Model& model);

// The bytes a save() of `saved` to `path` wrote, as a server sends them (the file and the .bin beside a .gltf); for
// the standard output ("-"), the .glb's. 0 when the file cannot be read back.
size_t saved_bytes(const std::string& path, const Model& saved);

// --- info ---

struct ClipInfo {
  int animation = -1;  // index in the file's animations
  std::string name;
  size_t frames = 0;
  double duration = 0;     // seconds, first to last frame
  size_t baked_bytes = 0;  // V × F × 3 floats
};

struct PrimitiveInfo {
  int node = -1;
  std::string node_name;
  int mesh = -1, primitive = -1;
  std::string kind;  // "morph", "skinned" or "morph+skinned"
  size_t vertices = 0, triangles = 0, welded_vertices = 0, connected_components = 0;
  std::vector<ClipInfo> clips;
  // In an encoded file: the version of the primitive's SEGMORPH_animation_compression stream (0: it has none, e.g. a
  // kept skin), whether that stream keeps morph targets, and whether it plays on the GPU from its model (a version-4
  // stream of clips: the three.js plugin's default playback; kept targets play as morph targets, other streams as
  // decoded frames).
  int stream_version = 0;
  bool kept_targets = false;
  bool gpu_playable = false;
};

struct InfoReport {
  std::vector<PrimitiveInfo> primitives;  // every animated primitive
  size_t animations = 0;                  // the file's animations
};

// The animated primitives of `model` (decoded first when it is encoded) and their clips, as sampled. Fails with
// nothing_to_do when nothing moves vertices.
Status info(const Model& model, const SampleSettings& settings, InfoReport& report, const Progress& progress = {});

// --- bake ---

struct BakeReport {
  size_t nodes = 0;   // animated nodes baked
  size_t frames = 0;  // frames in all (the first primitive of each node, every clip)
};

// Replaces every animated primitive of `model` by standard morph targets, one per sampled frame, played by one
// weights animation per clip (docs/baking.md). An encoded model is decoded first. The model is baked in place, so
// that a large input is not held twice: on failure it is left empty (load it again to use it).
Status bake(Model& model, const SampleSettings& settings, BakeReport* report = nullptr, const Progress& progress = {});

// --- encode ---

struct EncodeSettings {
  RateMode mode = RateMode::error;
  double target = 0.15;  // KG % (error) or bits per vertex per frame of the whole file (bpvf)
  SampleSettings sampling;
  size_t clusters = 0;     // motion clusters K; 0 chooses automatically
  int position_bits = 0;   // Draco position bits of the base meshes, 8 to 22; 0 chooses from the error target
  int normal_bits = 8;     // 4 to 16
  int texcoord_bits = 12;  // 4 to 30
  // What a skinned mesh without morph targets stores: its skin (kept, with coded tracks) or its sampled frames.
  // bpvf and lossless encodes bake; so does keep where a kept skin cannot reach the error target.
  enum class Skins { keep, bake } skins = Skins::keep;
  // What a morph-target mesh (unskinned, one node) stores: its targets or its frames; automatic encodes both ways
  // where it has at most half as many targets as frames and keeps the file smaller as a server sends it (an estimate
  // of its compressed size). Lossless encodes bake.
  enum class Targets { automatic, keep, bake } targets = Targets::automatic;
  // The residuals in the table code of stream version 2 (or 3): faster decoding, larger files. Lossy encodes only.
  bool fast_decode = false;
  // The latest animation stream version written, 1 to 4 (SEGMORPH_STREAM_VERSION_MAX): below 3, no frame references
  // and no motion contexts; below 4, no transform-coded residuals (the encoder uses each only where it makes a stream
  // smaller; version 4 only with error targets and without fast_decode); fast_decode needs 2.
  int max_stream_version = 4;
  // Only GPU-playable streams: every stream of clips version 4 (its model is what a player evaluates in the vertex
  // shader, docs/runtime.md), even where version 3 would be smaller; an encode where a primitive cannot have one at
  // the error target fails (UNSUPPORTED). Kept morph targets are coded as without it (they play as morph targets).
  // Error targets only, not with fast_decode or a max_stream_version below 4.
  bool gpu_playable = false;
  // Threads for the stages that split their work (the heat-diffusion eigenvectors of connected parts, side by side,
  // and of a part above 60,000 vertices, the cluster-count search, the motion fits, refinement and cluster weights,
  // each frame's reference, the residual steps' measurement and the motion step trials of rate control, the version-4
  // bases (the stream's beside the residual coding), the decodes and the comparison with the input at the end); 0:
  // every hardware thread. The output is the same bytes for every number.
  size_t threads = 0;
};

// One animated primitive of an original file, measured against the primitive of another file that plays it (verify),
// or against its own decoded encode (encode): the errors verify reports, for this primitive alone.
struct PrimitiveError {
  int node = -1;  // in the original
  std::string node_name;
  int mesh = -1, primitive = -1;
  size_t vertices = 0, frames = 0;  // the original's V and F (all clips)
  double kg_percent = 0, rmse_over_diagonal = 0, max_error_over_diagonal = 0;
};

// How encode stored a primitive: its animation as frames (a stream of its sampled frames: morph-target meshes baked
// and skinned meshes baked), as kept targets (a stream of its morph targets, played by its weights), as a kept skin
// (its mesh in Draco, played by its joints' coded tracks), or as a rigid mesh (in Draco, moved by its node's tracks).
enum class PrimitiveMode { frames, kept_targets, kept_skin, rigid };

// "frames", "kept_targets", "kept_skin" or "rigid".
const char* mode_name(PrimitiveMode mode);

// One primitive of the encoded file.
struct EncodedPrimitive {
  PrimitiveMode mode = PrimitiveMode::frames;
  int output_mesh = -1, output_primitive = -1;  // where it is in the encoded file
  size_t clusters = 0;                          // K of its stream (frames and kept targets)
  size_t bytes = 0;                             // its animation stream and its Draco mesh
  int stream_version = 0;                       // of its stream (0: none, e.g. a kept skin)
  bool gpu_playable = false;                    // a version-4 stream of clips: plays on the GPU from its model
  // The animated primitive of the input it plays, measured on the decoded encode as verify measures it. A rigid
  // mesh's primitive (error.mesh and primitive are its output_mesh and output_primitive) is measured in model space
  // at the key times of the clips that move its (first) node, its KG over the part's own spread; verify does not
  // measure rigid meshes, and EncodeReport::kg_percent leaves them out: their Draco step is set against the scene's
  // size, so a small part reads high on its own.
  PrimitiveError error;
};

struct EncodeReport {
  // Every animated primitive of the input (in the order of its animated nodes and their primitives), then the rigid
  // meshes' primitives.
  std::vector<EncodedPrimitive> primitives;
  size_t glb_bytes = 0;  // the encoded model as a .glb
  // The worst animated primitive's errors, measured on the decoded encode against the input (what verify reports;
  // rigid meshes are not in it).
  double kg_percent = 0, rmse_over_diagonal = 0, max_error_over_diagonal = 0;
  std::vector<StreamReport> streams;  // one per primitive coded as frames or kept targets
  double vertex_frames = 0;           // Σ V × F over the input's animated primitives and clips (what bpvf counts)
  size_t draco_bytes = 0;             // base meshes, kept skins and moving meshes
  size_t animation_bytes = 0;         // animation and track streams
  double ms_draco = 0;
  double ms_tracks = 0;   // coding the tracks (with kept skins: the search for their precision)
  double ms_measure = 0;  // decoding the encode and measuring it against the input
  double kept_skins_floor = 0;  // > 0: kept skins stayed at this KG % above the target, and were baked instead
  // Over `streams`: their clusters, the largest E(Π) before and after merging to K, and each stage's milliseconds.
  size_t clusters = 0;
  double e_pi_morse = 0, e_pi = 0;
  double ms_segmentation = 0, ms_motion = 0, ms_prediction = 0, ms_rate_control = 0, ms_entropy = 0;
};

// Encodes `input` (which may be any glTF with animation) into `output`: every animated primitive's first frame with
// KHR_draco_mesh_compression, its animation as a SEGMORPH_animation_compression stream, kept skins and moving meshes
// with Draco and their tracks coded. Fails with invalid_argument when the settings cannot be met (a bpvf target
// below what the rest of the file takes alone).
Status encode(const Model& input, const EncodeSettings& settings, Model& output, EncodeReport* report = nullptr,
              const Progress& progress = {});
// The same, consuming `input` (left empty): a large file is not held twice (the copy the other form makes).
Status encode(Model&& input, const EncodeSettings& settings, Model& output, EncodeReport* report = nullptr,
              const Progress& progress = {});

// --- decode ---

struct DecodeReport {
  size_t animation_bytes = 0;   // SEGMORPH streams read
  size_t primitives = 0;        // compressed primitives decoded
  size_t coded_animations = 0;  // animations whose tracks were coded
};

// What a compressed primitive's stream decoded to: for one that plays clips, its clips' frames (positions, V × 3 per
// frame); for one that keeps its morph targets, one clip whose T frames are the targets' POSITION displacements.
struct DecodedFrames {
  int mesh = -1, primitive = -1;
  bool targets = false;
  struct Clip {
    size_t vertex_count = 0, frame_count = 0;
    std::vector<float> positions;  // frame_count × vertex_count × 3
  };
  std::vector<Clip> clips;
};

// Restores standard glTF in place: morph targets in the form bake writes, kept morph targets, kept skins, plain
// meshes and float tracks (through the runtime decoder, include/segmorph/decoder.h). `frames`, when given, receives
// what every compressed primitive's stream decoded to, in the order of meshes and primitives. A model that is not
// encoded is left as it is (report->primitives and coded_animations 0).
Status decode(Model& model, DecodeReport* report = nullptr, std::vector<DecodedFrames>* frames = nullptr);

struct DecodeSettings {
  // Threads for each version-4 stream's frames (AnimationDecoder::set_threads); 0: every hardware thread. The output
  // is the same for every number.
  size_t threads = 0;
};
// The same with settings (the form above decodes on one thread).
Status decode(Model& model, const DecodeSettings& settings, DecodeReport* report = nullptr,
              std::vector<DecodedFrames>* frames = nullptr);

// Writes decoded frames to `path` as raw little-endian float32, primitive after primitive, clip after clip, frame after
// frame (the layout of `segmorph decode --frames` and examples/engine_decode), whole or not at all.
Status save_decoded_frames(const std::vector<DecodedFrames>& frames, const std::string& path);

// True when `path` ends in .glb or .gltf (case-insensitive): a name save() takes.
bool has_gltf_extension(const std::string& path);

// --- verify ---

struct VerifyReport {
  size_t vertices = 0;       // V of the original, over its animated primitives
  size_t frames = 0;         // F of its first animated primitive, over its clips
  double vertex_frames = 0;  // Σ V × F over its animated primitives and clips
  // The worst animated primitive's errors: KG in percent; RMSE and largest error over the bounding-box diagonal.
  double kg_percent = 0, rmse_over_diagonal = 0, max_error_over_diagonal = 0;
  size_t animation_bytes = 0;  // the compressed file's SEGMORPH streams
  std::vector<PrimitiveError> primitives;  // every animated primitive of the original
  // When verify fails, which model it is about: 0 the original (it cannot be sampled), 1 the compressed one.
  int failed_model = -1;

  // The primitive with the largest KG error (nullptr when there is none).
  const PrimitiveError* worst() const;
};

// Compares the animation of `compressed` with that of `original` (either may be encoded, baked, original or written
// by another tool: primitives and vertices are paired by trajectory, `compressed` is sampled at `original`'s frame
// times). A failed Status is about `compressed`, unless it is original's sampling that failed (report.failed_model).
Status verify(const Model& original, const Model& compressed, const SampleSettings& settings, VerifyReport& report,
              const Progress& progress = {});

// Bounds on a verified file, for a CI gate; negative: none.
struct VerifyBounds {
  double max_error = -1;  // KG %
  double max_bpvf = -1;   // bits per vertex per frame of the whole compressed file
};
enum class VerifyBound { none, max_error, max_bpvf };

// The first bound the verified file exceeds (the error, then the rate), with `bytes` its size (input_bytes).
VerifyBound exceeded_bound(const VerifyReport& report, size_t bytes, const VerifyBounds& bounds);

}  // namespace segmorph
