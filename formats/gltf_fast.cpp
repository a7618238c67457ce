// gltf_fast.cpp - the fast path of the glTF load: simdjson parses a GLB's JSON chunk (its DOM,
// a tape it builds several times faster than RapidJSON's DOM, which tinygltf uses) and only what
// a bake reads is copied into the plain doc::Document that gltf_convert.cpp reads (gltf_parts.h);
// the BIN chunk is left where it lies and its accessors are read there. Members a bake does not
// read (names of views, accessors, meshes; materials, modes) are still type-checked as tinygltf
// would, so a file either path refuses is refused here too.
//
// tinygltf's parse was most of a big rig's load: its own DOM walk looks up every member by name
// (FindMember), copies every extension and extra into its Value tree, and builds structs of a
// few hundred bytes for each of tens of thousands of accessors and channels. Here each object's
// members are walked once.
//
// simdjson reads JSON as RapidJSON does with three exceptions, each sent to tinygltf: it refuses
// invalid UTF-8, lone surrogates and integers past 64 bits (RapidJSON takes them: parse_fast
// gives up), and it rounds every number correctly where RapidJSON's full precision does not
// (screened for in doubles_read_alike, gltf_fast_screen.cpp).
//
// The path is strict: whatever it does not handle exactly as tinygltf would (Draco, meshopt,
// buffers or data-URI images, cameras, lights, a member of another type than tinygltf reads, a key
// given twice, anything tinygltf would refuse) makes it give up, and the tinygltf path loads the
// file: a bad file gets tinygltf's messages and the converter's, as before.
#include <algorithm>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>
#include <sys/mman.h>

#include <simdjson.h>

#include "gltf_parts.h"

namespace cbgltf {

namespace {

using Value = simdjson::dom::element;

struct NotFast {}; // thrown to give the file to the tinygltf path

[[noreturn]] void not_fast() { throw NotFast{}; }

int as_int(Value v) // tinygltf's GetInt on RapidJSON's IsInt: an integer token in int32's range
{
    int64_t i;
    if (v.get_int64().get(i) || i < INT32_MIN || i > INT32_MAX) not_fast();
    return (int)i;
}

size_t as_size(Value v) // IsUint64: an integer token from 0 to 2^64 - 1
{
    uint64_t u;
    if (v.get_uint64().get(u)) not_fast();
    return (size_t)u;
}

double as_number(Value v) // GetDouble: an integer converted, or the correctly rounded double
{
    double d;
    if (v.get_double().get(d)) not_fast();
    return d;
}

std::string_view checked_string(Value v) // tinygltf copies a C string: one with a NUL in it goes there
{
    std::string_view s;
    if (v.get_string().get(s) || std::memchr(s.data(), 0, s.size())) not_fast();
    return s;
}

void check_string(Value v) { checked_string(v); }

std::string as_string(Value v) { return std::string(checked_string(v)); }

simdjson::dom::array as_array(Value v)
{
    simdjson::dom::array a;
    if (v.get_array().get(a)) not_fast();
    return a;
}

simdjson::dom::object as_object(Value v)
{
    simdjson::dom::object o;
    if (v.get_object().get(o)) not_fast();
    return o;
}

std::vector<int> int_array(Value v)
{
    simdjson::dom::array a = as_array(v);
    std::vector<int> out;
    out.reserve(a.size());
    for (Value e : a) out.push_back(as_int(e));
    return out;
}

std::vector<double> number_array(Value v)
{
    simdjson::dom::array a = as_array(v);
    std::vector<double> out;
    out.reserve(a.size());
    for (Value e : a) out.push_back(as_number(e));
    return out;
}

// glTF's keys are short: up to 16 bytes they are compared as two loads of 4 or 8 bytes each,
// overlapping in the middle (every byte read lies in both keys), without a call to memcmp.
template <class Word> bool same_ends(const char *a, const char *b, size_t n)
{
    Word a0, a1, b0, b1;
    std::memcpy(&a0, a, sizeof a0), std::memcpy(&a1, a + n - sizeof a1, sizeof a1);
    std::memcpy(&b0, b, sizeof b0), std::memcpy(&b1, b + n - sizeof b1, sizeof b1);
    return ((a0 ^ b0) | (a1 ^ b1)) == 0;
}

inline bool same_key(std::string_view key, std::string_view wanted)
{
    size_t n = wanted.size();
    if (key.size() != n) return false;
    if (n >= 8 && n <= 16) return same_ends<uint64_t>(key.data(), wanted.data(), n);
    if (n >= 4 && n < 8) return same_ends<uint32_t>(key.data(), wanted.data(), n);
    return std::memcmp(key.data(), wanted.data(), n) == 0;
}

// Calls f(i, value) for each member whose key is keys[i]; other keys are not read. Returns the
// bits of the keys found, so callers check the required ones. A key given twice gives up:
// tinygltf reads the first, simdjson keeps both. Keys are compared whole, NULs and all, as
// RapidJSON's FindMember compares them for tinygltf.
template <size_t N, class F> unsigned members(Value o, const std::string_view (&keys)[N], F f)
{
    static_assert(N <= 32, "a bit per key");
    unsigned seen = 0;
    for (simdjson::dom::key_value_pair m : as_object(o)) {
        for (size_t i = 0; i < N; ++i)
            if (same_key(m.key, keys[i])) {
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

template <class F> void each(Value array, F f)
{
    for (Value e : as_array(array)) f(e);
}

void parse_asset(Value o)
{
    static constexpr std::string_view keys[] = {"version"};
    require(members(o, keys, [](size_t, Value v) { check_string(v); }), 1);
}

void parse_buffer(Value o, size_t *byte_length)
{
    static constexpr std::string_view keys[] = {"byteLength", "uri", "name"};
    unsigned seen = members(o, keys, [&](size_t i, Value v) {
        if (i == 0) *byte_length = as_size(v);
        else if (i == 1) not_fast(); // external files and data URIs: the tinygltf path
        else check_string(v);
    });
    require(seen, 1);
}

void parse_view(Value o, doc::BufferView *view)
{
    static constexpr std::string_view keys[] = {"buffer", "byteOffset", "byteLength", "byteStride", "name"};
    unsigned seen = members(o, keys, [&](size_t i, Value v) {
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

void parse_sparse(Value o, doc::Accessor *a)
{
    static constexpr std::string_view keys[] = {"count", "indices", "values"};
    static constexpr std::string_view indices_keys[] = {"bufferView", "byteOffset", "componentType"};
    a->sparse.isSparse = true;
    a->sparse.indices.byteOffset = a->sparse.values.byteOffset = 0; // tinygltf's defaults
    unsigned seen = members(o, keys, [&](size_t i, Value v) {
        if (i == 0) {
            a->sparse.count = as_int(v);
        } else if (i == 1) {
            auto &ix = a->sparse.indices;
            unsigned got = members(v, indices_keys, [&](size_t k, Value x) {
                (k == 0 ? ix.bufferView : k == 1 ? ix.byteOffset : ix.componentType) = as_int(x);
            });
            require(got, 1 | 4);
        } else {
            auto &vals = a->sparse.values;
            unsigned got = members(v, indices_keys, [&](size_t k, Value x) {
                if (k == 2) return; // not a member of values: not read
                (k == 0 ? vals.bufferView : vals.byteOffset) = as_int(x);
            });
            require(got, 1);
        }
    });
    require(seen, 1 | 2 | 4);
}

int accessor_type(std::string_view t)
{
    static constexpr struct {
        std::string_view name;
        int type;
    } types[] = {{"SCALAR", TINYGLTF_TYPE_SCALAR}, {"VEC2", TINYGLTF_TYPE_VEC2}, {"VEC3", TINYGLTF_TYPE_VEC3},
                 {"VEC4", TINYGLTF_TYPE_VEC4},     {"MAT2", TINYGLTF_TYPE_MAT2}, {"MAT3", TINYGLTF_TYPE_MAT3},
                 {"MAT4", TINYGLTF_TYPE_MAT4}};
    for (const auto &e : types)
        if (t == e.name) return e.type;
    not_fast();
}

void parse_accessor(Value o, doc::Accessor *a)
{
    static constexpr std::string_view keys[] = {"bufferView", "byteOffset", "normalized", "componentType",
                                                "count",      "type",       "sparse",     "name"};
    unsigned seen = members(o, keys, [&](size_t i, Value v) {
        switch (i) {
        case 0: a->bufferView = as_int(v); break;
        case 1: a->byteOffset = as_size(v); break;
        case 2:
            if (v.get_bool().get(a->normalized)) not_fast();
            break;
        case 3: {
            size_t t = as_size(v);
            if (t < TINYGLTF_COMPONENT_TYPE_BYTE || t > TINYGLTF_COMPONENT_TYPE_DOUBLE) not_fast();
            a->componentType = (int)t;
            break;
        }
        case 4: a->count = as_size(v); break;
        case 5: a->type = accessor_type(checked_string(v)); break;
        case 6: parse_sparse(v, a); break;
        default: check_string(v);
        }
    });
    require(seen, 8 | 16 | 32);
}

void parse_primitive(Value o, doc::Primitive *p)
{
    static constexpr std::string_view keys[] = {"attributes", "indices", "material", "mode"};
    unsigned seen = members(o, keys, [&](size_t i, Value v) {
        if (i == 0) {
            simdjson::dom::object attributes = as_object(v);
            p->attributes.reserve(attributes.size());
            for (simdjson::dom::key_value_pair m : attributes) {
                if (std::memchr(m.key.data(), 0, m.key.size())) not_fast();
                std::string name(m.key);
                if (p->attribute(name.c_str())) not_fast();
                p->attributes.emplace_back(std::move(name), as_int(m.value));
            }
        } else if (i == 1) {
            p->indices = as_int(v);
        } else if (i == 2) {
            p->material = as_int(v);
        } else {
            as_int(v); // mode: not read
        }
    });
    require(seen, 1);
}

void parse_mesh(Value o, doc::Mesh *mesh)
{
    static constexpr std::string_view keys[] = {"primitives", "name"};
    members(o, keys, [&](size_t i, Value v) {
        if (i == 1) return check_string(v);
        each(v, [&](Value e) {
            mesh->primitives.emplace_back();
            parse_primitive(e, &mesh->primitives.back());
        });
    });
}

void parse_node(Value o, doc::Node *n)
{
    static constexpr std::string_view keys[] = {"name", "skin", "mesh", "children", "matrix", "translation", "rotation", "scale"};
    std::vector<double> trs[3];
    unsigned seen = members(o, keys, [&](size_t i, Value v) {
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

void parse_skin(Value o, doc::Skin *s)
{
    static constexpr std::string_view keys[] = {"name", "joints", "skeleton", "inverseBindMatrices"};
    unsigned seen = members(o, keys, [&](size_t i, Value v) {
        switch (i) {
        case 0: s->name = as_string(v); break;
        case 1: s->joints = int_array(v); break;
        case 2: s->skeleton = as_int(v); break;
        default: s->inverseBindMatrices = as_int(v);
        }
    });
    require(seen, 2);
}

void parse_channel(Value o, doc::AnimationChannel *ch)
{
    static constexpr std::string_view keys[] = {"sampler", "target"};
    static constexpr std::string_view target_keys[] = {"node", "path"};
    unsigned seen = members(o, keys, [&](size_t i, Value v) {
        if (i == 0) return void(ch->sampler = as_int(v));
        unsigned got = members(v, target_keys, [&](size_t k, Value x) {
            if (k == 0) ch->target_node = as_int(x);
            else ch->target_path = as_string(x);
        });
        require(got, 1 | 2);
    });
    require(seen, 1 | 2);
}

void parse_animation(Value o, doc::Animation *a)
{
    static constexpr std::string_view keys[] = {"channels", "samplers", "name"};
    static constexpr std::string_view sampler_keys[] = {"input", "output", "interpolation"};
    members(o, keys, [&](size_t i, Value v) {
        if (i == 2) return void(a->name = as_string(v));
        if (i == 0) {
            a->channels.reserve(as_array(v).size());
            return each(v, [&](Value e) {
                a->channels.emplace_back();
                parse_channel(e, &a->channels.back());
            });
        }
        a->samplers.reserve(as_array(v).size());
        each(v, [&](Value e) {
            a->samplers.emplace_back();
            doc::AnimationSampler *s = &a->samplers.back();
            unsigned got = members(e, sampler_keys, [&](size_t k, Value x) {
                if (k == 2) s->interpolation = as_string(x);
                else (k == 0 ? s->input : s->output) = as_int(x);
            });
            require(got, 1 | 2);
        });
    });
}

void parse_scene(Value o, doc::Scene *s)
{
    static constexpr std::string_view keys[] = {"nodes", "name"};
    members(o, keys, [&](size_t i, Value v) {
        if (i == 0) s->nodes = int_array(v);
        else check_string(v);
    });
}

// Images are never decoded, but tinygltf refuses some: only those it surely takes stay here.
// An image given by uri goes to tinygltf, which reads its bytes (kept for `mesh`).
void parse_image(Value o, const doc::Document &g, doc::Image *image)
{
    static constexpr std::string_view keys[] = {"bufferView", "uri", "mimeType"};
    unsigned seen = members(o, keys, [&](size_t i, Value v) {
        if (i == 0) image->bufferView = as_int(v);
        else if (i == 1) not_fast();
        else image->mimeType = as_string(v);
    });
    int view = image->bufferView;
    if (!(seen & 1) || view < 0 || (size_t)view >= g.bufferViews.size() || g.bufferViews[(size_t)view].buffer < 0 ||
        (size_t)g.bufferViews[(size_t)view].buffer >= g.buffers.size())
        not_fast();
}

// {"index": i, "texCoord": n}
void parse_texture_info(Value o, doc::Material *m)
{
    static constexpr std::string_view keys[] = {"index", "texCoord"};
    unsigned seen = members(o, keys, [&](size_t i, Value v) {
        if (i == 0) m->base_color_texture = as_int(v);
        else m->base_color_texcoord = as_int(v);
    });
    require(seen, 1);
}

void parse_pbr(Value o, doc::Material *m)
{
    static constexpr std::string_view keys[] = {"baseColorFactor", "baseColorTexture", "metallicFactor", "roughnessFactor"};
    members(o, keys, [&](size_t i, Value v) {
        if (i == 0) {
            std::vector<double> f = number_array(v);
            if (f.size() != 4) not_fast();
            std::copy(f.begin(), f.end(), m->base_color);
        } else if (i == 1) {
            parse_texture_info(v, m);
        } else {
            (i == 2 ? m->metallic : m->roughness) = as_number(v);
        }
    });
}

void parse_material(Value o, doc::Material *m)
{
    static constexpr std::string_view keys[] = {"emissiveFactor", "name", "pbrMetallicRoughness", "alphaMode", "alphaCutoff",
                                                "doubleSided"};
    members(o, keys, [&](size_t i, Value v) {
        bool b;
        if (i == 0 && number_array(v).size() != 3) not_fast();
        if (i == 1) m->name = as_string(v);
        if (i == 2) parse_pbr(v, m);
        if (i == 3) m->alpha_mode = as_string(v);
        if (i == 4) m->alpha_cutoff = as_number(v);
        if (i == 5 && v.get_bool().get(b)) not_fast();
        if (i == 5) m->double_sided = b;
    });
}

void parse_texture(Value o, doc::Texture *t)
{
    static constexpr std::string_view keys[] = {"source", "sampler"};
    members(o, keys, [&](size_t i, Value v) { (i == 0 ? t->source : t->sampler) = as_int(v); });
}

void parse_sampler(Value o, doc::Sampler *s)
{
    static constexpr std::string_view keys[] = {"magFilter", "minFilter", "wrapS", "wrapT"};
    members(o, keys, [&](size_t i, Value v) {
        int *field[] = {&s->magFilter, &s->minFilter, &s->wrapS, &s->wrapT};
        *field[i] = as_int(v);
    });
}

template <class T, class F> void parse_list(Value v, std::vector<T> *out, F parse)
{
    simdjson::dom::array a = as_array(v);
    out->reserve(a.size()); // saturates at 2^24 - 1: a hint
    for (Value e : a) {
        out->emplace_back();
        parse(e, &out->back());
    }
}

// The sections in tinygltf's order: images are checked against the views and buffers.
void parse_document(Value root, doc::Document *g, size_t *byte_length)
{
    static constexpr std::string_view keys[] = {"asset", "extensionsUsed", "extensionsRequired", "buffers", "bufferViews",
                                                "accessors", "meshes", "nodes", "scenes", "scene", "animations", "skins",
                                                "cameras", "images", "materials", "textures", "samplers", "extensions"};
    Value later[18];
    unsigned seen = members(root, keys, [&](size_t i, Value v) { later[i] = v; });
    auto given = [seen](int k) { return (seen >> k) & 1; };
    require(seen, 1);
    if (given(12) || given(17)) not_fast(); // cameras and KHR_lights_punctual: tinygltf checks them closely
    parse_asset(later[0]);
    for (int k = 1; k <= 2; ++k)
        if (given(k)) each(later[k], [&](Value e) {
                if (k == 2) g->extensionsRequired.push_back(as_string(e));
                else check_string(e);
            });
    if (given(3)) {
        parse_list(later[3], &g->buffers, [&](Value o, Bytes *) { parse_buffer(o, byte_length); });
        if (g->buffers.size() > 1) not_fast(); // only the BIN chunk: every other buffer has a uri
    }
    if (given(4)) parse_list(later[4], &g->bufferViews, parse_view);
    if (given(5)) parse_list(later[5], &g->accessors, parse_accessor);
    if (given(6)) parse_list(later[6], &g->meshes, parse_mesh);
    if (given(7)) parse_list(later[7], &g->nodes, parse_node);
    if (given(8)) parse_list(later[8], &g->scenes, parse_scene);
    if (given(9)) g->defaultScene = as_int(later[9]);
    if (given(10)) parse_list(later[10], &g->animations, parse_animation);
    if (given(11)) parse_list(later[11], &g->skins, parse_skin);
    if (given(13)) parse_list(later[13], &g->images, [&](Value o, doc::Image *image) { parse_image(o, *g, image); });
    if (given(14)) parse_list(later[14], &g->materials, parse_material);
    if (given(15)) parse_list(later[15], &g->textures, parse_texture);
    if (given(16)) parse_list(later[16], &g->samplers, parse_sampler);
    // tinygltf refuses a primitive whose indices accessor, or its view, does not exist.
    for (const doc::Mesh &mesh : g->meshes)
        for (const doc::Primitive &p : mesh.primitives)
            if (p.indices >= 0) {
                if ((size_t)p.indices >= g->accessors.size()) not_fast();
                int view = g->accessors[(size_t)p.indices].bufferView;
                if (view < 0 || (size_t)view >= g->bufferViews.size()) not_fast();
            }
}

// Where the OS offers transparent huge pages: the whole 2 MB pages inside [p, p + bytes).
void advise_huge_pages(void *p, size_t bytes)
{
#if defined(MADV_HUGEPAGE)
    const uintptr_t huge = (uintptr_t)2 << 20;
    uintptr_t from = ((uintptr_t)p + huge - 1) & ~(huge - 1), to = ((uintptr_t)p + bytes) & ~(huge - 1);
    if (from < to) madvise(reinterpret_cast<void *>(from), to - from, MADV_HUGEPAGE);
#else
    (void)p, (void)bytes;
#endif
}

// simdjson sizes its buffers by the JSON's length (structural indexes 4 bytes a byte of JSON,
// the tape 8, strings 5/3) and fills them once, front to back: fresh memory that a big rig's
// 1.4 MB JSON touched in 1,250 page faults of 4 KB, a third of the parse. Allocated here (the
// parse then finds them large enough and keeps them), their whole huge pages take a fault each.
// They are the parser's own members, public though marked private in simdjson 3's headers; a
// failed allocation is left for the parse to report.
void allocate_on_huge_pages(simdjson::dom::parser *parser, size_t json_length)
{
    if (parser->allocate(json_length) || parser->doc.allocate(json_length)) return;
    advise_huge_pages(parser->implementation->structural_indexes.get(), json_length * sizeof(uint32_t));
    advise_huge_pages(parser->doc.tape.get(), json_length * sizeof(uint64_t));
    advise_huge_pages(parser->doc.string_buf.get(), json_length / 3 * 5);
}

} // namespace

bool parse_fast(const unsigned char *data, size_t size, size_t settled, doc::Document *out, BinInPlace *in_place)
{
    size_t json_length, bin_at, bin_length;
    if (!glb_chunks(data, size, &json_length, &bin_at, &bin_length)) return false;
    const char *json = reinterpret_cast<const char *>(data + 20);
    // Draco and meshopt (KHR_draco_mesh_compression, EXT_ and KHR_meshopt_compression) are
    // decoded on the tinygltf path; one search finds all three. A NUL (RapidJSON's end of the
    // text) fails tinygltf's parse of the chunk.
    if (mentions(json, json_length, "_compression") || std::memchr(json, 0, json_length)) return false;
    if (!doubles_read_alike(json, json_length)) return false;
    // simdjson may read up to SIMDJSON_PADDING bytes past the text (never using them): the BIN
    // chunk's first bytes where they are settled, else a copy's padding.
    simdjson::padded_string copy;
    if (20 + json_length + simdjson::SIMDJSON_PADDING > settled) {
        copy = simdjson::padded_string(json, json_length);
        if (!copy.data()) throw std::bad_alloc();
        json = copy.data();
    }
    simdjson::dom::parser parser;
    allocate_on_huge_pages(&parser, json_length);
    Value root;
    if (parser.parse(json, json_length, false).get(root)) return false; // tinygltf's message for it
    doc::Document g;
    size_t byte_length = 0;
    try {
        parse_document(root, &g, &byte_length);
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
        return cbgltf::parse_fast(data, size, size, &g, nullptr);
    } catch (const std::exception &) {
        return false;
    }
}
