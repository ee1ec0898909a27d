# The layout as a test (docs/architecture.md): codec/common/ includes nothing of decode/ or encode/, codec/decode/
# nothing of encode/, neither anything of the pipeline (segmorph/segmorph.h, segmorph/encoding.h); the runtime
# decoder's library defines no symbol of the encoder (its range encoder, models' encode(), stream and track
# writers); extensions/ includes nothing of converter/; converter/cli/ nothing but the public API. Run as
# cmake -DSOURCE_DIR=... -DDECODER_LIBRARY=... -DNM=... -P layout.cmake.
set(CODEC_DIR ${SOURCE_DIR}/codec)
set(problems)
foreach(side common decode)
  if(side STREQUAL "common")
    set(forbidden "decode/|encode/|segmorph/segmorph\\.h|segmorph/encoding\\.h")
  else()
    set(forbidden "encode/|segmorph/segmorph\\.h|segmorph/encoding\\.h")
  endif()
  file(GLOB_RECURSE sources ${CODEC_DIR}/${side}/*.h ${CODEC_DIR}/${side}/*.cpp)
  foreach(source ${sources})
    file(STRINGS ${source} includes REGEX "^#include \"(${forbidden})")
    foreach(line ${includes})
      list(APPEND problems "${source}: ${line}")
    endforeach()
  endforeach()
endforeach()

# extensions/ is below the pipeline: none of converter/'s folders or headers, nor the pipeline API.
file(GLOB sources ${SOURCE_DIR}/extensions/*.h ${SOURCE_DIR}/extensions/*.cpp)
foreach(source ${sources})
  set(converter "(bake|caches|cli|decoding|encoding|gltf|sampling|verify)/|pipeline\\.h|file_names\\.h")
  file(STRINGS ${source} includes REGEX "^#include \"(${converter}|segmorph/segmorph\\.h)")
  foreach(line ${includes})
    list(APPEND problems "${source}: ${line}")
  endforeach()
endforeach()

# converter/cli/ is printing over the pipeline API: its own files, the public headers and output_file.h (the
# temporary files a signal removes) only.
file(GLOB sources ${SOURCE_DIR}/converter/cli/*.h ${SOURCE_DIR}/converter/cli/*.cpp)
foreach(source ${sources})
  file(STRINGS ${source} includes REGEX "^#include \"")
  list(FILTER includes EXCLUDE REGEX "^#include \"(cli/|segmorph/|gltf/output_file\\.h\")")
  foreach(line ${includes})
    list(APPEND problems "${source}: ${line}")
  endforeach()
endforeach()

execute_process(COMMAND ${NM} -C --defined-only ${DECODER_LIBRARY} OUTPUT_VARIABLE symbols RESULT_VARIABLE failed)
if(failed)
  message(FATAL_ERROR "${NM} could not read ${DECODER_LIBRARY}")
endif()
string(REGEX MATCHALL "[^\n]*(RangeEncoder|::encode\\(|encode_residuals|encode_table_residuals|encode_tracks|write_stream|transform_symbols|segmorph::encode_animation)[^\n]*" defined "${symbols}")
foreach(line ${defined})
  list(APPEND problems "the decoder library defines an encoder symbol: ${line}")
endforeach()
string(FIND "${symbols}" "welded_vertex_normals" normals)
if(normals EQUAL -1)
  list(APPEND problems "the decoder library has no normals (decode/normals.cpp)")
endif()

if(problems)
  list(JOIN problems "\n" text)
  message(FATAL_ERROR "${text}")
endif()
message(STATUS "layout: common/ and decode/ include nothing of encode/, the decoder defines no encoder symbol, "
               "extensions/ includes nothing of converter/, cli/ only the public API")
