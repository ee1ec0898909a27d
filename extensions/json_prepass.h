// A pass over a glTF's JSON before tinygltf parses it, for valid files tinygltf 2.7 refuses.
//
// KHR_draco_mesh_compression lets a compressed primitive keep an `indices` accessor with no bufferView (the
// triangles are in the Draco data); tinygltf 2.7 rejects any indices accessor without a bufferView. Such
// primitives lose their `indices` here; the Draco decoder supplies the triangles (decode_draco_primitives).
#pragma once

#include <string>

#include "segmorph/status.h"

namespace segmorph {

// Rewrites `json` (a whole glTF JSON document) as described above. Sets `changed` when it removed anything;
// leaves `json` as it was otherwise. Every other byte of the document is kept as written. Fails on JSON it
// cannot parse (nesting deeper than 256 levels included), which tinygltf would refuse too.
Status drop_draco_indices(std::string& json, bool& changed);

// Fails when arrays and objects nest deeper than `max_depth` (strings skipped): tinygltf 2.7 parses JSON
// recursively and overflows the stack on a file of some ten thousand '[' (a 60 KB file crashed it).
Status check_json_nesting(const std::string& json, int max_depth = 512);

// Fails (unsupported) when the document uses an extension whose data segmorph cannot read, naming it and how to
// undo it: EXT_meshopt_compression and KHR_meshopt_compression (tinygltf would otherwise refuse such a file with a
// message about buffer lengths).
Status refuse_unreadable_extensions(const std::string& json);

}  // namespace segmorph
