# check_conformance_gpu.gd - the runtime conformance cases (tests/runtimes/conformance.h) with the addon's GPU path
# in Godot 4.6's web build: the vertex function of crowdbake_herd.gdshader as CrowdbakeHerd builds it (its palette's
# layout and precision, its include inlined), reading each instance's numbers from the herd's instance texture at
# herd_time, skins every vertex of every instance of every group; what it would hand Godot as VERTEX (the skinned,
# cross-faded point) is written instead, bit for bit, into the pixels of a SubViewport and read back, as the GL
# harness reads it back with transform feedback (Godot has none). Run by check_addon.gd (whose case lines it prints).
#
# Only the vertex function's last lines (the view transform) and the fragment function are replaced: the point p
# goes out as a flat varying, each vertex of the case's mesh is a 9x1-pixel quad placed by POSITION, and the
# fragment writes the 32 bits of p's x, y and z, 4 bits a channel (n x 17 of 255): the Compatibility renderer's
# unshaded 8-bit output moves a channel by up to 3 of 255 (measured here), which whole bytes do not survive. The worst |got - expected| against the C runtime's CASE.expected must stay within
# 1e-5 x max(1, model height), like check_conformance.gd's CPU path; broken-row-off-by-one must miss by more than ten
# times that. Each case runs its two groups (two times), every instance and vertex.
extends RefCounted

const ROOT := "/crowdbake"
const ADDON := ROOT + "/addons/crowdbake"
const DIR := ROOT + "/bakes/conformance"
const BROKEN := ["broken-row-off-by-one", "broken-timed-map-ignored"] # faults in the instances, which the addon plays
const WIDTH := 756 # pixels a row: a multiple of 9, so that no vertex's 9 pixels wrap
const INSTANCES_PER_ROW := 256 # CrowdbakeHerd's

var addon # check_addon.gd's instance: _begin, _end, _herd_script

func _init(addon_check) -> void:
	addon = addon_check

func run() -> void:
	var cases: Array = JSON.parse_string(FileAccess.get_file_as_string(DIR + "/cases.json"))["cases"]
	var viewport := SubViewport.new()
	viewport.render_target_update_mode = SubViewport.UPDATE_ALWAYS
	viewport.transparent_bg = true
	viewport.own_world_3d = true
	viewport.add_child(Camera3D.new())
	addon.check.add_child(viewport)
	# Local rows (.pal version 6) once the addon composes them (its `local_rows`, docs/pal-format.md).
	var composes := FileAccess.get_file_as_string(ADDON + "/crowdbake_palette.gdshaderinc").contains("local_rows")
	await _check_packing()
	var far_cases := 0
	for c in cases:
		if c.get("local", false) and not composes:
			continue
		if c.has("bone_pass") or (c["broken"] and not (c["name"] in BROKEN)):
			continue # the bone pass is the shaders' own; the other faults live in GLSL or storage
		var per_vertex: PackedVector3Array = await _check_case(c, viewport, false)
		await _check_case(c, viewport, true, per_vertex)
		if not c["broken"]: # a fault's miss says nothing within the far tier's looser bound; both builds in turns
			await _check_case(c, viewport, true, per_vertex, true, far_cases % 2 == 1)
			far_cases += 1
	viewport.queue_free()

# The case's points drawn per vertex, or (bone_pass) through the herd's bone pass, which must also come within the
# tolerance of `per_vertex` (the per-vertex path's points). Returns the points read back.
# halves: the bone pass's far tier (every instance marked as under the animation LOD's halves_pixels()), as the herd
# draws it then: the shader's far-only build (no lo-half fetches) and the pass drawing the hi halves' rows alone, within the herd's halves_error() of the C runtime's points (the bound its threshold assumes),
# and further from them than the full path's tolerance somewhere (the tier took effect). mixed: a herd with near and
# far instances instead: every other instance (the first of each group among them) marked far, drawn through the
# build that reads each instance's tier (the pass drawing both blocks): the far instances' points within
# halves_error(), the near ones' within the full path's tolerance (each instance drawn in its own tier).
func _check_case(c: Dictionary, viewport: SubViewport, bone_pass: bool, per_vertex := PackedVector3Array(), halves := false,
		mixed := false) -> PackedVector3Array:
	var tier := ("hi halves mixed " if mixed else "hi halves ") if halves else ""
	var name: String = ("gpu conformance bone pass " + tier if bone_pass else "gpu conformance ") + c["name"]
	addon._begin(name)
	var all := PackedVector3Array()
	var pal = load(ADDON + "/crowdbake_palette.gd").new()
	if not pal.load_file(DIR + "/" + c["pal"]):
		addon._end(name, pal.error)
		return all
	var height := FileAccess.get_file_as_bytes(DIR + "/" + c["pal"]).decode_float(104) # the header's model_height
	var tolerance := 1e-5 * maxf(1.0, height)
	var positions := FileAccess.get_file_as_bytes(DIR + "/" + c["mesh"]["positions"]).to_float32_array()
	var verts := positions.size() / 3
	var herd: MultiMeshInstance3D = addon._herd_script.new() if bone_pass else null
	var material := _material(pal, verts, herd, halves and not mixed)
	if material == null:
		addon._end(name, "crowdbake_herd.gdshader's vertex function no longer ends with the view transform")
		return all
	var full_tolerance := tolerance
	if halves: # instances marked far (_instances), as CrowdbakeHerd marks one under halves_pixels() tall
		tolerance = herd.halves_error()
	var node := MultiMeshInstance3D.new()
	node.multimesh = MultiMesh.new()
	node.multimesh.transform_format = MultiMesh.TRANSFORM_3D
	node.multimesh.mesh = _mesh(c, positions)
	node.multimesh.mesh.surface_set_material(0, material)
	node.multimesh.custom_aabb = AABB(Vector3.ONE * -1e6, Vector3.ONE * 2e6) # never culled: POSITION places it
	viewport.add_child(node)
	var expected := FileAccess.get_file_as_bytes(DIR + "/" + c["expected"]).to_float32_array()
	var worst := 0.0
	var worst_near := 0.0 # mixed: the worst of the near instances' points
	var apart := 0.0 # the bone pass's points from the per-vertex path's
	var at := 0
	if herd != null:
		viewport.add_child(herd)
		herd.set_process(false) # the case sets its uniforms
	for group in c["groups"]:
		var count: int = group["instances"].size()
		var rows := ceili(float(count * verts * 9) / WIDTH)
		viewport.size = Vector2i(WIDTH, rows)
		material.set_shader_parameter("cb_height", rows)
		material.set_shader_parameter("herd_time", float(group["time"]))
		material.set_shader_parameter("instances", _instances(group["instances"], halves, mixed))
		if herd != null: # the herd's bone pass for this group's instances, drawn into its SubViewport
			herd.count = count
			herd._build_bone_pass()
			herd._bone_material.set_shader_parameter("herd_time", float(group["time"]))
			herd._bone_material.set_shader_parameter("instances", _instances(group["instances"], halves, mixed))
		node.multimesh.instance_count = count
		await RenderingServer.frame_post_draw
		await RenderingServer.frame_post_draw
		var image := viewport.get_texture().get_image()
		image.convert(Image.FORMAT_RGBA8)
		var got := _decode(image.get_data(), count * verts)
		for i in got.size():
			var want := Vector3(expected[at], expected[at + 1], expected[at + 2])
			var d := (got[i] - want).abs()
			worst = maxf(worst, maxf(d.x, maxf(d.y, d.z))) if got[i].is_finite() else INF
			if mixed and (i / verts) % 2 == 1:
				worst_near = maxf(worst_near, maxf(d.x, maxf(d.y, d.z))) if got[i].is_finite() else INF
			if herd != null and all.size() < per_vertex.size():
				var e := (got[i] - per_vertex[all.size()]).abs()
				apart = maxf(apart, maxf(e.x, maxf(e.y, e.z))) if got[i].is_finite() else INF
			all.append(got[i])
			at += 3
	node.queue_free()
	if herd != null:
		herd.queue_free()
	var ratio := worst / tolerance
	print("crowdbake-check: %s: worst %s (%s of the tolerance)%s%s" % [name, String.num_scientific(worst), String.num(ratio, 3),
			", %s from the per-vertex path (%s of the tolerance)" % [String.num_scientific(apart), String.num(apart / tolerance, 3)] if herd else "",
			"; near instances %s (%s of the full path's tolerance)" % [String.num_scientific(worst_near), String.num(worst_near / full_tolerance, 3)] if mixed else ""])
	var why := ""
	if halves and not c["broken"] and worst <= full_tolerance:
		why = "the hi halves came within the full path's tolerance %s (worst %s): the far tier did not take effect" % [full_tolerance, worst]
	elif mixed and not c["broken"] and not worst_near <= full_tolerance:
		why = "the mixed herd's near instances are %s from the C runtime's points, over the full path's tolerance %s: drawn in the far tier" % [worst_near, full_tolerance]
	elif herd != null and (per_vertex.size() != all.size() or not apart <= tolerance) and not c["broken"]:
		why = "the bone pass's points are %s from the per-vertex path's (%d of %d points), tolerance %s" % [apart, all.size(), per_vertex.size(), tolerance]
	elif at != expected.size():
		why = "%d of %d expected numbers compared" % [at, expected.size()]
	elif c["broken"] and ratio <= 10.0:
		why = "the broken case came within %s of the tolerance" % ratio
	elif not c["broken"] and not ratio <= 1.0:
		why = "worst %s, tolerance %s" % [worst, tolerance]
	addon._end(name, why)
	return all

# The herd's material for `pal` (CrowdbakeHerd._material: the shipped shader, defines and uniforms), its output
# replaced by the capture described at the top.
# With `bone_herd` (a herd not yet set up), the material skins from that herd's bone pass (built per group).
func _material(pal, verts: int, bone_herd: MultiMeshInstance3D = null, far_only := false) -> ShaderMaterial:
	var herd: MultiMeshInstance3D = bone_herd if bone_herd else addon._herd_script.new()
	herd.palette = pal
	herd.playing = false
	herd.uses_bone_pass = bone_herd != null
	var material: ShaderMaterial = herd._material(far_only)
	herd._far_only = far_only # its pass (built per group) draws the hi halves' rows alone
	if bone_herd == null:
		herd.free()
	var code: String = material.shader.code
	var view_transform := code.find("\tVERTEX = (MODELVIEW_MATRIX")
	var vertex_end := code.find("\n}", view_transform)
	var fragment := code.find("void fragment()")
	if view_transform < 0 or vertex_end < 0 or fragment < vertex_end:
		return null
	code = code.substr(0, view_transform) + """	cb_p = p;
	int cb_base = (INSTANCE_ID * cb_vertices + int(UV.x + 0.5)) * 9; // the first of the vertex's 9 pixels
	cb_x0 = cb_base %% %d;
	vec2 cb_at = vec2(float(cb_x0) + 9.0 * UV2.x, float(cb_base / %d) + UV2.y);
	POSITION = vec4(cb_at / vec2(%d.0, float(cb_height)) * 2.0 - 1.0, 0.0, 1.0);
""" % [WIDTH, WIDTH, WIDTH] + code.substr(vertex_end, fragment - vertex_end) + """void fragment() {
	int k = int(FRAGCOORD.x) - cb_x0; // 0-2 x, 3-5 y, 6-8 z: bits 0-11, 12-23, 24-31
	uint bits = floatBitsToUint(k < 3 ? cb_p.x : (k < 6 ? cb_p.y : cb_p.z)) >> uint(12 * (k % 3));
	ALBEDO = vec3(uvec3(bits, bits >> 4u, bits >> 8u) & uvec3(15u)) * (17.0 / 255.0);
}
"""
	code = code.replace("render_mode skip_vertex_transform;", """render_mode skip_vertex_transform, unshaded, cull_disabled, shadows_disabled;
varying flat vec3 cb_p;
varying flat int cb_x0;
uniform int cb_vertices;
uniform int cb_height;""")
	var shader := Shader.new()
	shader.code = code
	var capture: ShaderMaterial = material.duplicate()
	capture.shader = shader
	capture.set_shader_parameter("cb_vertices", verts)
	if bone_herd != null:
		var drawn: Array[ShaderMaterial] = [capture]
		bone_herd.materials = drawn
	return capture

# The case's mesh as quads: vertex v of the case is 6 vertices (two triangles over its 9 pixels), each with v's
# position, joints and weights, UV.x = v and UV2 the quad's corner.
static func _mesh(c: Dictionary, positions: PackedFloat32Array) -> ArrayMesh:
	var joints := FileAccess.get_file_as_bytes(DIR + "/" + c["mesh"]["joints"])
	var weights := FileAccess.get_file_as_bytes(DIR + "/" + c["mesh"]["weights"]).to_float32_array()
	var corners := [Vector2(0, 0), Vector2(1, 0), Vector2(1, 1), Vector2(0, 0), Vector2(1, 1), Vector2(0, 1)]
	var vertex := PackedVector3Array()
	var uv := PackedVector2Array()
	var uv2 := PackedVector2Array()
	var bones := PackedInt32Array()
	var bone_weights := PackedFloat32Array()
	for v in positions.size() / 3:
		for corner in corners:
			vertex.append(Vector3(positions[v * 3], positions[v * 3 + 1], positions[v * 3 + 2]))
			uv.append(Vector2(v, 0))
			uv2.append(corner)
			for k in 4:
				bones.append(joints.decode_u16(v * 8 + k * 2))
				bone_weights.append(weights[v * 4 + k])
	var arrays := []
	arrays.resize(Mesh.ARRAY_MAX)
	arrays[Mesh.ARRAY_VERTEX] = vertex
	var normals := PackedVector3Array()
	normals.resize(vertex.size())
	normals.fill(Vector3.UP)
	var tangents := PackedFloat32Array()
	for v in vertex.size():
		tangents.append_array([1.0, 0.0, 0.0, 1.0])
	arrays[Mesh.ARRAY_NORMAL] = normals # the herd's shader skins them too (unused here)
	arrays[Mesh.ARRAY_TANGENT] = tangents
	arrays[Mesh.ARRAY_TEX_UV] = uv
	arrays[Mesh.ARRAY_TEX_UV2] = uv2
	arrays[Mesh.ARRAY_BONES] = bones
	arrays[Mesh.ARRAY_WEIGHTS] = bone_weights
	var mesh := ArrayMesh.new()
	mesh.add_surface_from_arrays(Mesh.PRIMITIVE_TRIANGLES, arrays)
	return mesh

# CrowdbakeHerd's instance texture: per instance the clip's four numbers, the previous clip's, the fade's start
# and length (conformance.h's instance floats 4..13); far: every instance in the bone pass's far tier (float 10).
static func _instances(instances: Array, far := false, every_other := false) -> ImageTexture:
	var rows := ceili(float(instances.size()) / INSTANCES_PER_ROW)
	var texels := PackedFloat32Array()
	texels.resize(rows * INSTANCES_PER_ROW * 12)
	for i in instances.size():
		for k in 10:
			texels[i * 12 + k] = instances[i][4 + k]
		texels[i * 12 + 10] = 1.0 if far and (not every_other or i % 2 == 0) else 0.0
	return ImageTexture.create_from_image(Image.create_from_data(INSTANCES_PER_ROW * 3, rows, false, Image.FORMAT_RGBAF,
			texels.to_byte_array()))

# The points the pixels hold: 9 pixels a point, x y z as three pixels each, 4 bits in each of R, G, B (n x 17).
static func _decode(rgba: PackedByteArray, points: int) -> PackedVector3Array:
	var out := PackedVector3Array()
	out.resize(points)
	var bits := PackedByteArray()
	bits.resize(4)
	for i in points:
		var p := Vector3()
		for axis in 3:
			var value := 0
			for n in 9: # nibbles, lowest first
				value |= roundi(rgba[(i * 9 + axis * 3 + n / 3) * 4 + n % 3] / 17.0) << (4 * n)
			bits.encode_u32(0, value & 0xffffffff)
			p[axis] = bits.decode_float(0)
		out[i] = p
	return out

# The bone pass's premise: a use_hdr_2d SubViewport (RGBA16F in the Compatibility renderer) gives a second shader
# every finite half float written into it bit for bit, and a bone's rows split into hi and lo halves
# (cb_bone_pass_texel) add back to within 2^-22 of each float (+ 2^-25, half the smallest subnormal half), the
# way the herd's vertex shader reads them. Columns 0-31: hashed half bit patterns (every exponent but the
# infinities'); columns 32-61: five bones of hashed floats (exponents 2^-63 to 2^0) and sines, 6 texels each.
func _check_packing() -> void:
	var name := "bone pass: half floats in an RGBA16F SubViewport come back bit for bit; hi + lo halves within 2^-22"
	addon._begin(name)
	var includes := "#define CB_LAYOUT 2\n#define CB_U16 1\n" + FileAccess.get_file_as_string(ADDON + "/crowdbake_palette.gdshaderinc") \
			+ FileAccess.get_file_as_string(ADDON + "/crowdbake_bone_pass.gdshaderinc")
	var value := """
uint cb_hash(uint x, uint y) {
	uint h = x * 2654435761u ^ (y * 2246822519u + 12345u);
	h ^= h >> 13u;
	h *= 3266489917u;
	return h ^ (h >> 16u);
}
uint cb_half_bits(ivec2 xy, int c) { // a finite half's bits: exponent 31 (infinity, NaN) moved to 15
	uint h = cb_hash(uint(xy.x * 4 + c), uint(xy.y)) & 65535u;
	return ((h >> 10u) & 31u) == 31u ? h ^ 0x4000u : h;
}
vec4 cb_halves(ivec2 xy) {
	return vec4(unpackHalf2x16(cb_half_bits(xy, 0)).x, unpackHalf2x16(cb_half_bits(xy, 1)).x, unpackHalf2x16(cb_half_bits(xy, 2)).x,
			unpackHalf2x16(cb_half_bits(xy, 3)).x);
}
float cb_value(int x, int y) {
	return x % 2 == 0 ? uintBitsToFloat((cb_hash(uint(x), uint(y)) & ~0x40000000u) | 0x20000000u) : sin(float(x) * 7.1 + float(y)) * 1234.5678;
}
mat4 cb_matrix(int bone, int y) {
	mat4 m = mat4(0.0);
	for (int k = 0; k < 16; k++) {
		m[k / 4][k % 4] = cb_value(bone * 16 + k, y);
	}
	return m;
}
"""
	var writer := _canvas("shader_type canvas_item;\nrender_mode unshaded, blend_disabled;\n" + includes + value
			+ "void fragment() {\n\tivec2 xy = ivec2(FRAGCOORD.xy);\n"
			+ "\tCOLOR = xy.x < 32 ? cb_halves(xy) : cb_bone_pass_affine_texel(cb_matrix((xy.x - 32) / 6, xy.y), (xy.x - 32) % 6);\n}\n", true)
	var reader := _canvas("shader_type canvas_item;\nrender_mode unshaded, blend_disabled;\n" + includes + value
			+ "uniform highp sampler2D written : filter_nearest, repeat_disable;\nvoid fragment() {\n\tivec2 xy = ivec2(FRAGCOORD.xy);\n"
			+ "\tvec4 got = texelFetch(written, xy, 0);\n\tbool ok;\n\tif (xy.x < 32) {\n"
			+ "\t\tok = uvec4(packHalf2x16(got.xy), packHalf2x16(got.zw), 0u, 0u) == uvec4(packHalf2x16(cb_halves(xy).xy), packHalf2x16(cb_halves(xy).zw), 0u, 0u);\n"
			+ "\t} else if (xy.x < 62 && (xy.x - 32) % 6 < 3) {\n"
			+ "\t\tint k = (xy.x - 32) % 6;\n\t\tmat4 m = cb_matrix((xy.x - 32) / 6, xy.y);\n"
			+ "\t\tvec4 want = vec4(m[0][k], m[1][k], m[2][k], m[3][k]);\n"
			+ "\t\tok = all(lessThanEqual(abs(got + texelFetch(written, xy + ivec2(3, 0), 0) - want), abs(want) * exp2(-22.0) + exp2(-25.0)));\n"
			+ "\t} else {\n\t\tok = true;\n\t}\n"
			+ "\tCOLOR = ok ? vec4(0.0, 1.0, 0.0, 1.0) : vec4(1.0, 0.0, 0.0, 1.0);\n}\n", false)
	reader.get_child(0).material.set_shader_parameter("written", writer.get_texture())
	for k in 3:
		await RenderingServer.frame_post_draw
	var fetched := reader.get_texture().get_image()
	fetched.convert(Image.FORMAT_RGBA8)
	var data := fetched.get_data()
	var wrong := [0, 0] # half patterns (32 x 16 texels), rows (5 bones x 3 rows x 16)
	for y in 16:
		for x in 62:
			if x < 32 or (x - 32) % 6 < 3:
				wrong[0 if x < 32 else 1] += 0 if data[(y * 64 + x) * 4 + 1] == 255 and data[(y * 64 + x) * 4] == 0 else 1
	writer.queue_free()
	reader.queue_free()
	print("crowdbake-check: half floats: %d of 512 texels of half bit patterns fetched differ; %d of 240 rows of hi + lo halves off by more than 2^-22" % wrong)
	addon._end(name, "" if wrong == [0, 0] else "%d texels of half patterns differ, %d rows of hi + lo halves are off" % wrong)

# A 64x16 SubViewport (RGBA16F with `hdr`) drawn by a canvas_item shader of `code` over a ColorRect, in the tree.
func _canvas(code: String, hdr: bool) -> SubViewport:
	var viewport := SubViewport.new()
	viewport.size = Vector2i(64, 16)
	viewport.use_hdr_2d = hdr
	viewport.render_target_update_mode = SubViewport.UPDATE_ALWAYS
	viewport.transparent_bg = true
	viewport.disable_3d = true
	var rect := ColorRect.new()
	rect.size = Vector2(64, 16)
	var shader := Shader.new()
	shader.code = code
	var material := ShaderMaterial.new()
	material.shader = shader
	rect.material = material
	viewport.add_child(rect)
	addon.check.add_child(viewport)
	return viewport
