// pipeline IN OUT.glb [ERROR]: what a build tool does with segmorph's pipeline API (docs/library.md): load a glTF
// file, encode it to a KG error target (percent, default 0.15), read the report, write the result; then decode a copy
// back to standard glTF and verify the encoded file against the original, as a CI gate would. Prints one JSON line.
#include <cstdio>
#include <cstdlib>
#include <string>

#include <segmorph/segmorph.h>

int main(int argc, char** argv) {
  if (argc < 3 || argc > 4) {
    std::fprintf(stderr, "usage: pipeline IN OUT.glb [ERROR]\n");
    return 2;
  }
  const std::string in = argv[1], out = argv[2];
  auto fail = [](const std::string& file, const segmorph::Status& status) {
    std::fprintf(stderr, "pipeline: %s: %s\n", file.c_str(), status.message().c_str());
    return 1;
  };

  segmorph::Model original;
  segmorph::Status status = segmorph::Model::load(in, original);
  if (!status.ok()) return fail(in, status);

  segmorph::EncodeSettings settings;  // --error 0.15, kept skins, automatic clusters and precisions
  if (argc == 4) settings.target = std::atof(argv[3]);
  segmorph::Model encoded;
  segmorph::EncodeReport report;
  status = segmorph::encode(original, settings, encoded, &report,
                            [](const std::string& line) { std::fprintf(stderr, "pipeline: %s\n", line.c_str()); });
  if (!status.ok()) return fail(in, status);
  status = encoded.save(out);
  if (!status.ok()) return fail(out, status);

  segmorph::Model decoded = encoded;  // standard glTF, as a viewer without the extension would need it
  segmorph::DecodeReport decode_report;
  status = segmorph::decode(decoded, &decode_report);
  if (!status.ok()) return fail(out, status);

  segmorph::VerifyReport verify_report;
  status = segmorph::verify(original, encoded, settings.sampling, verify_report);
  if (!status.ok()) return fail(out, status);
  const size_t bytes = segmorph::file_bytes(out, encoded);
  std::printf("{\"output\":\"%s\",\"bytes\":%zu,\"bpvf\":%.4f,\"kg_percent\":%.6g,\"streams\":%zu,"
              "\"decoded_primitives\":%zu,\"within_target\":%s}\n",
              out.c_str(), bytes, 8.0 * double(bytes) / verify_report.vertex_frames, verify_report.kg_percent,
              report.streams.size(), decode_report.primitives,
              verify_report.kg_percent <= settings.target ? "true" : "false");
  return verify_report.kg_percent <= settings.target ? 0 : 1;
}
