// tinygltf_config.h - how crowdbake builds tinygltf (Debian's header-only libtinygltf-dev): no
// images, Draco on, RapidJSON as its JSON parser. Every translation unit that includes
// tiny_gltf.h includes it through this file, so all of them see the same classes.
#ifndef CB_TINYGLTF_CONFIG_H
#define CB_TINYGLTF_CONFIG_H
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#define TINYGLTF_ENABLE_DRACO
/* RapidJSON, not nlohmann::json: the JSON of a large rig parses ~5x faster. Its CRT allocator
 * keeps tinygltf free of the global "active document" the pool allocator needs; full
 * precision makes numbers the correctly rounded doubles strtod gives (the default may be an
 * ulp off: node transforms written as decimals would then bake differently). */
#define RAPIDJSON_PARSE_DEFAULT_FLAGS kParseFullPrecisionFlag
#define TINYGLTF_USE_RAPIDJSON
#define TINYGLTF_USE_RAPIDJSON_CRTALLOCATOR
#define TINYGLTF_NO_INCLUDE_RAPIDJSON
#include <rapidjson/document.h>
#include <rapidjson/prettywriter.h>
#include <rapidjson/rapidjson.h>
#include <rapidjson/stringbuffer.h>
#include <rapidjson/writer.h>
#include <tiny_gltf.h>

#endif
