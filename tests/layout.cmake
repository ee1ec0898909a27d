# The layout as a test (docs/architecture.md): codec/common/ includes nothing of decode/ or encode/, codec/decode/
# nothing of encode/, neither anything of the pipeline (segmorph/segmorph.h, segmorph/encoding.h); the runtime
# decoder's library defines no symbol of the encoder (its range encoder, models' encode(), stream and track
# writers); extensions/ includes nothing of converter/. Run as cmake -DSOURCE_DIR=... -DDECODER_LIBRARY=... -DNM=...
# -P layout.cmake.
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
  file(STRINGS ${source} includes REGEX
       "^#include \"((bake|caches|cli|decoding|encoding|gltf|sampling|verify)/|pipeline\\.h|file_names\\.h|segmorph/segmorph\\.h)")
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
               "extensions/ includes nothing of converter/")
