// gltf_fast.cpp - the fast path of the glTF load: RapidJSON parses a GLB's JSON chunk in place
// (a DOM on its pool allocator, full-precision numbers, as tinygltf is built) and only what a
// bake reads is copied into the plain doc::Document that gltf_convert.cpp reads (gltf_parts.h);
// the BIN chunk is left where it lies and its accessors are read there. Members a bake does not
// read (names of views, accessors, meshes; materials, modes) are still type-checked as tinygltf
// would, so a file either path refuses is refused here too.
//
// tinygltf's parse was most of a big rig's load: its own DOM walk looks up every member by name
// (FindMember), copies every extension and extra into its Value tree, and builds structs of a
// few hundred bytes for each of tens of thousands of accessors and channels. Here each object's
// members are walked once.
//
// The path is strict: whatever it does not handle exactly as tinygltf would (Draco, meshopt,
// buffers or data-URI images, cameras, lights, a member of another type than tinygltf reads, a key
// given twice, anything tinygltf would refuse) makes it give up, and the tinygltf path loads the
// file: a bad file gets tinygltf's messages and the converter's, as before.
#include <cstring>
#include <string>
#include <vector>

#include "gltf_parts.h"

namespace cbgltf {

namespace {

using rapidjson::Value;

struct NotFast {}; // thrown to give the file to the tinygltf path

[[noreturn]] void not_fast() { throw NotFast{}; }

int as_int(const Value &v) // tinygltf's GetInt, less its truncation of 64-bit values
{
    if (!v.IsInt()) not_fast();
    return v.GetInt();
}

size_t as_size(const Value &v)
{
    if (!v.IsUint64()) not_fast();
    return (size_t)v.GetUint64();
}

void check_string(const Value &v) // tinygltf copies a C string: one with a NUL in it goes there
{
    if (!v.IsString() || std::strlen(v.GetString()) != v.GetStringLength()) not_fast();
}

std::string as_string(const Value &v)
{
    check_string(v);
    return std::string(v.GetString(), v.GetStringLength());
}

const Value &as_array(const Value &v)
{
    if (!v.IsArray()) not_fast();
    return v;
}

std::vector<int> int_array(const Value &v)
{
    std::vector<int> out;
    out.reserve(as_array(v).Size());
    for (const Value &e : v.GetArray()) out.push_back(as_int(e));
    return out;
}

std::vector<double> number_array(const Value &v)
{
    std::vector<double> out;
    out.reserve(as_array(v).Size());
    for (const Value &e : v.GetArray()) {
        if (!e.IsNumber()) not_fast();
        out.push_back(e.GetDouble());
    }
    return out;
}

// Calls f(i, value) for each member whose key is keys[i]; other keys are not read. Returns the
// bits of the keys found, so callers check the required ones. A key given twice gives up:
// tinygltf reads the first, RapidJSON keeps both.
template <size_t N, class F> unsigned members(const Value &o, const char *const (&keys)[N], F f)
{
    static_assert(N <= 32, "a bit per key");
    if (!o.IsObject()) not_fast();
    unsigned seen = 0;
    for (const auto &m : o.GetObject()) {
        const char *k = m.name.GetString();
        for (size_t i = 0; i < N; ++i)
            if (k[0] == keys[i][0] && std::strcmp(k, keys[i]) == 0) {
                if (seen & (1u << i)) not_fast();
                seen |= 1u << i;
                f(i, m.value);
                break;
            }
    }
    return seen;
}

void require(unsigned seen, unsigned bits)
{
    if ((seen & bits) != bits) not_fast();
}

template <class F> void each(const Value &array, F f)
{
    for (const Value &e : as_array(array).GetArray()) f(e);
}

void parse_asset(const Value &o)
{
    static const char *const keys[] = {"version"};
    require(members(o, keys, [](size_t, const Value &v) { check_string(v); }), 1);
}

void parse_buffer(const Value &o, size_t *byte_length)
{
    static const char *const keys[] = {"byteLength", "uri", "name"};
    unsigned seen = members(o, keys, [&](size_t i, const Value &v) {
        if (i == 0) *byte_length = as_size(v);
        else if (i == 1) not_fast(); // external files and data URIs: the tinygltf path
        else check_string(v);
    });
    require(seen, 1);
}

void parse_view(const Value &o, doc::BufferView *view)
{
    static const char *const keys[] = {"buffer", "byteOffset", "byteLength", "byteStride", "name"};
    unsigned seen = members(o, keys, [&](size_t i, const Value &v) {
        switch (i) {
        case 0: view->buffer = as_int(v); break;
        case 1: view->byteOffset = as_size(v); break;
        case 2: view->byteLength = as_size(v); break;
        case 3: view->byteStride = as_size(v); break;
        default: check_string(v);
        }
    });
    require(seen, 1 | 4);
    if (view->byteStride > 252 || view->byteStride % 4) not_fast(); // tinygltf refuses it
}

void parse_sparse(const Value &o, doc::Accessor *a)
{
    static const char *const keys[] = {"count", "indices", "values"};
    static const char *const indices_keys[] = {"bufferView", "byteOffset", "componentType"};
    a->sparse.isSparse = true;
    a->sparse.indices.byteOffset = a->sparse.values.byteOffset = 0; // tinygltf's defaults
    unsigned seen = members(o, keys, [&](size_t i, const Value &v) {
        if (i == 0) {
            a->sparse.count = as_int(v);
        } else if (i == 1) {
            auto &ix = a->sparse.indices;
            unsigned got = members(v, indices_keys, [&](size_t k, const Value &x) {
                (k == 0 ? ix.bufferView : k == 1 ? ix.byteOffset : ix.componentType) = as_int(x);
            });
            require(got, 1 | 4);
        } else {
            auto &vals = a->sparse.values;
            unsigned got = members(v, indices_keys, [&](size_t k, const Value &x) {
                if (k == 2) return; // not a member of values: not read
                (k == 0 ? vals.bufferView : vals.byteOffset) = as_int(x);
            });
            require(got, 1);
        }
    });
    require(seen, 1 | 2 | 4);
}

int accessor_type(const std::string &t)
{
    static const struct {
        const char *name;
        int type;
    } types[] = {{"SCALAR", TINYGLTF_TYPE_SCALAR}, {"VEC2", TINYGLTF_TYPE_VEC2}, {"VEC3", TINYGLTF_TYPE_VEC3},
                 {"VEC4", TINYGLTF_TYPE_VEC4},     {"MAT2", TINYGLTF_TYPE_MAT2}, {"MAT3", TINYGLTF_TYPE_MAT3},
                 {"MAT4", TINYGLTF_TYPE_MAT4}};
    for (const auto &e : types)
        if (t == e.name) return e.type;
    not_fast();
}

void parse_accessor(const Value &o, doc::Accessor *a)
{
    static const char *const keys[] = {"bufferView", "byteOffset", "normalized", "componentType",
                                       "count",      "type",       "sparse",     "name"};
    unsigned seen = members(o, keys, [&](size_t i, const Value &v) {
        switch (i) {
        case 0: a->bufferView = as_int(v); break;
        case 1: a->byteOffset = as_size(v); break;
        case 2:
            if (!v.IsBool()) not_fast();
            a->normalized = v.GetBool();
            break;
        case 3: {
            size_t t = as_size(v);
            if (t < TINYGLTF_COMPONENT_TYPE_BYTE || t > TINYGLTF_COMPONENT_TYPE_DOUBLE) not_fast();
            a->componentType = (int)t;
            break;
        }
        case 4: a->count = as_size(v); break;
        case 5: a->type = accessor_type(as_string(v)); break;
        case 6: parse_sparse(v, a); break;
        default: check_string(v);
        }
    });
    require(seen, 8 | 16 | 32);
}

void parse_primitive(const Value &o, doc::Primitive *p)
{
    static const char *const keys[] = {"attributes", "indices", "material", "mode"};
    unsigned seen = members(o, keys, [&](size_t i, const Value &v) {
        if (i == 0) {
            if (!v.IsObject()) not_fast();
            p->attributes.reserve(v.MemberCount());
            for (const auto &m : v.GetObject()) {
                std::string name = as_string(m.name);
                if (p->attribute(name.c_str())) not_fast();
                p->attributes.emplace_back(std::move(name), as_int(m.value));
            }
        } else if (i == 1) {
            p->indices = as_int(v);
        } else {
            as_int(v); // material, mode: not read
        }
    });
    require(seen, 1);
}

void parse_mesh(const Value &o, doc::Mesh *mesh)
{
    static const char *const keys[] = {"primitives", "name"};
    members(o, keys, [&](size_t i, const Value &v) {
        if (i == 1) return check_string(v);
        each(v, [&](const Value &e) {
            mesh->primitives.emplace_back();
            parse_primitive(e, &mesh->primitives.back());
        });
    });
}

void parse_node(const Value &o, doc::Node *n)
{
    static const char *const keys[] = {"name", "skin", "mesh", "children", "matrix", "translation", "rotation", "scale"};
    std::vector<double> trs[3];
    unsigned seen = members(o, keys, [&](size_t i, const Value &v) {
        switch (i) {
        case 0: n->name = as_string(v); break;
        case 1: n->skin = as_int(v); break;
        case 2: n->mesh = as_int(v); break;
        case 3: n->children = int_array(v); break;
        case 4: n->matrix = number_array(v); break;
        default: trs[i - 5] = number_array(v);
        }
    });
    if (seen & 16) return; // tinygltf reads no T/R/S beside a matrix
    n->translation = std::move(trs[0]);
    n->rotation = std::move(trs[1]);
    n->scale = std::move(trs[2]);
}

void parse_skin(const Value &o, doc::Skin *s)
{
    static const char *const keys[] = {"name", "joints", "skeleton", "inverseBindMatrices"};
    unsigned seen = members(o, keys, [&](size_t i, const Value &v) {
        switch (i) {
        case 0: s->name = as_string(v); break;
        case 1: s->joints = int_array(v); break;
        case 2: s->skeleton = as_int(v); break;
        default: s->inverseBindMatrices = as_int(v);
        }
    });
    require(seen, 2);
}

void parse_channel(const Value &o, doc::AnimationChannel *ch)
{
    static const char *const keys[] = {"sampler", "target"};
    static const char *const target_keys[] = {"node", "path"};
    unsigned seen = members(o, keys, [&](size_t i, const Value &v) {
        if (i == 0) return void(ch->sampler = as_int(v));
        unsigned got = members(v, target_keys, [&](size_t k, const Value &x) {
            if (k == 0) ch->target_node = as_int(x);
            else ch->target_path = as_string(x);
        });
        require(got, 1 | 2);
    });
    require(seen, 1 | 2);
}

void parse_animation(const Value &o, doc::Animation *a)
{
    static const char *const keys[] = {"channels", "samplers", "name"};
    static const char *const sampler_keys[] = {"input", "output", "interpolation"};
    members(o, keys, [&](size_t i, const Value &v) {
        if (i == 2) return void(a->name = as_string(v));
        if (i == 0) {
            a->channels.reserve(as_array(v).Size());
            return each(v, [&](const Value &e) {
                a->channels.emplace_back();
                parse_channel(e, &a->channels.back());
            });
        }
        a->samplers.reserve(as_array(v).Size());
        each(v, [&](const Value &e) {
            a->samplers.emplace_back();
            doc::AnimationSampler *s = &a->samplers.back();
            unsigned got = members(e, sampler_keys, [&](size_t k, const Value &x) {
                if (k == 2) s->interpolation = as_string(x);
                else (k == 0 ? s->input : s->output) = as_int(x);
            });
            require(got, 1 | 2);
        });
    });
}

void parse_scene(const Value &o, doc::Scene *s)
{
    static const char *const keys[] = {"nodes", "name"};
    members(o, keys, [&](size_t i, const Value &v) {
        if (i == 0) s->nodes = int_array(v);
        else check_string(v);
    });
}

// Images are never decoded, but tinygltf refuses some: only those it surely takes stay here.
void check_image(const Value &o, const doc::Document &g)
{
    static const char *const keys[] = {"bufferView", "uri"};
    int view = -1;
    unsigned seen = members(o, keys, [&](size_t i, const Value &v) {
        if (i == 0) view = as_int(v);
        else if (as_string(v).rfind("data:", 0) == 0) not_fast();
    });
    if (seen == 3 || seen == 0) not_fast();
    if (seen == 1 && (view < 0 || (size_t)view >= g.bufferViews.size() || g.bufferViews[(size_t)view].buffer < 0 ||
                      (size_t)g.bufferViews[(size_t)view].buffer >= g.buffers.size()))
        not_fast();
}

void check_material(const Value &o)
{
    static const char *const keys[] = {"emissiveFactor"};
    members(o, keys, [](size_t, const Value &v) {
        if (number_array(v).size() != 3) not_fast();
    });
}

template <class T, class F> void parse_list(const Value &v, std::vector<T> *out, F parse)
{
    out->resize(as_array(v).Size());
    size_t i = 0;
    for (const Value &e : v.GetArray()) parse(e, &(*out)[i++]);
}

// The sections in tinygltf's order: images are checked against the views and buffers.
void parse_document(const Value &root, doc::Document *g, size_t *byte_length)
{
    static const char *const keys[] = {"asset", "extensionsUsed", "extensionsRequired", "buffers", "bufferViews",
                                       "accessors", "meshes", "nodes", "scenes", "scene", "animations", "skins",
                                       "cameras", "images", "materials", "textures", "samplers", "extensions"};
    const Value *later[18] = {};
    unsigned seen = members(root, keys, [&](size_t i, const Value &v) { later[i] = &v; });
    require(seen, 1);
    if (later[12] || later[17]) not_fast(); // cameras and KHR_lights_punctual: tinygltf checks them closely
    parse_asset(*later[0]);
    for (int k = 1; k <= 2; ++k)
        if (later[k]) each(*later[k], [&](const Value &e) {
                if (k == 2) g->extensionsRequired.push_back(as_string(e));
                else check_string(e);
            });
    if (later[3]) {
        parse_list(*later[3], &g->buffers, [&](const Value &o, Bytes *) { parse_buffer(o, byte_length); });
        if (g->buffers.size() > 1) not_fast(); // only the BIN chunk: every other buffer has a uri
    }
    if (later[4]) parse_list(*later[4], &g->bufferViews, parse_view);
    if (later[5]) parse_list(*later[5], &g->accessors, parse_accessor);
    if (later[6]) parse_list(*later[6], &g->meshes, parse_mesh);
    if (later[7]) parse_list(*later[7], &g->nodes, parse_node);
    if (later[8]) parse_list(*later[8], &g->scenes, parse_scene);
    if (later[9]) g->defaultScene = as_int(*later[9]);
    if (later[10]) parse_list(*later[10], &g->animations, parse_animation);
    if (later[11]) parse_list(*later[11], &g->skins, parse_skin);
    if (later[13]) each(*later[13], [&](const Value &o) { check_image(o, *g); });
    if (later[14]) each(*later[14], check_material);
    for (int k = 15; k <= 16; ++k)
        if (later[k]) each(*later[k], [](const Value &o) {
                if (!o.IsObject()) not_fast();
            });
    // tinygltf refuses a primitive whose indices accessor, or its view, does not exist.
    for (const doc::Mesh &mesh : g->meshes)
        for (const doc::Primitive &p : mesh.primitives)
            if (p.indices >= 0) {
                if ((size_t)p.indices >= g->accessors.size()) not_fast();
                int view = g->accessors[(size_t)p.indices].bufferView;
                if (view < 0 || (size_t)view >= g->bufferViews.size()) not_fast();
            }
}

// A GLB that tinygltf takes: a JSON chunk (4-byte aligned) and at most a BIN chunk, as
// LoadBinaryFromMemory checks them.
bool glb_chunks(const unsigned char *data, size_t size, size_t *json_length, size_t *bin_at, size_t *bin_length)
{
    if (size < 20 || std::memcmp(data, "glTF", 4) != 0) return false;
    uint64_t length = le32(data + 8), json_end = 20ull + le32(data + 12);
    if (le32(data + 4) != 2 || length > size || json_end > length || le32(data + 12) < 4 || json_end % 4 || le32(data + 16) != 0x4E4F534Au)
        return false;
    *json_length = le32(data + 12);
    *bin_at = 0, *bin_length = 0;
    if (json_end == length) return true;
    if (json_end + 12 > length) return false;
    uint64_t chunk = le32(data + json_end);
    if (chunk < 4 || chunk % 4 || json_end + chunk > length || le32(data + json_end + 4) != 0x004E4942u) return false;
    *bin_at = (size_t)json_end + 8, *bin_length = (size_t)chunk;
    return true;
}

} // namespace

bool parse_fast(const unsigned char *data, size_t size, doc::Document *out, BinInPlace *in_place)
{
    size_t json_length, bin_at, bin_length;
    if (!glb_chunks(data, size, &json_length, &bin_at, &bin_length)) return false;
    const char *json = reinterpret_cast<const char *>(data + 20);
    // Draco and meshopt (KHR_draco_mesh_compression, EXT_ and KHR_meshopt_compression) are
    // decoded on the tinygltf path; one search finds all three. A NUL would end the in-place
    // parse where tinygltf's parse of the whole chunk fails.
    if (mentions(json, json_length, "_compression") || std::memchr(json, 0, json_length)) return false;
    std::vector<char> text(json, json + json_length);
    text.push_back('\0');
    rapidjson::Document doc;
    doc.ParseInsitu<rapidjson::kParseInsituFlag | rapidjson::kParseFullPrecisionFlag>(text.data());
    if (doc.HasParseError()) return false;
    doc::Document g;
    size_t byte_length = 0;
    try {
        parse_document(doc, &g, &byte_length);
    } catch (const NotFast &) {
        return false;
    }
    if (!g.buffers.empty()) {
        if (!bin_length || byte_length > bin_length) return false; // tinygltf's messages
        if (in_place) {
            in_place->at = bin_at, in_place->length = byte_length;
        } else {
            g.buffers[0].assign(data + bin_at, data + bin_at + byte_length);
        }
    }
    *out = std::move(g);
    return true;
}

} // namespace cbgltf

extern "C" bool cb_gltf_fast_path_applies(const unsigned char *data, size_t size)
{
    cbgltf::doc::Document g;
    try {
        return cbgltf::parse_fast(data, size, &g, nullptr);
    } catch (const std::exception &) {
        return false;
    }
}
