# check.gd - runs inside Godot 4.6's web build (tests/runtimes/godot/run_godot.mjs loads it as an autoload).
# The addon's resources and CrowdbakeHerd are checked by check_addon.gd, which it runs last.
# It compiles every shipped .gdshader in every layout, with a u16 and a float palette, by drawing a
# skinned MultiMesh with it, and loads and runs the shipped GDScript loader on real bakes. Each case
# prints
#   crowdbake-check: begin NAME / crowdbake-check: end NAME
# so the runner can attribute Godot's own error lines (shader compile errors reach only the log) to
# it; a case also prints "crowdbake-check: fail NAME | WHY" when its own checks fail. Cases named
# "broken:" (a deliberately broken shader) and "expect-error:" (a refusal that must be reported
# with push_error) pass only when Godot logged an error in them.
extends Node

const ROOT := "/crowdbake"
const SHIPPED := ROOT + "/addons/crowdbake"
const BAKES := ROOT + "/bakes"
const LAYOUTS := ["mat4", "affine", "qpos"]

var _loader_script: GDScript
var _viewport: SubViewport
var _herd: MultiMeshInstance3D
var _failures := 0
var _shader_count := 0

func _ready() -> void:
	_viewport = SubViewport.new()
	_viewport.size = Vector2i(64, 64)
	_viewport.render_target_update_mode = SubViewport.UPDATE_ALWAYS
	_viewport.transparent_bg = true
	_viewport.own_world_3d = true
	add_child(_viewport)
	var camera := Camera3D.new()
	camera.position = Vector3(0, 0, 3)
	_viewport.add_child(camera)
	_herd = MultiMeshInstance3D.new()
	_viewport.add_child(_herd)
	await _run()
	print("crowdbake-check: done, %d failed" % _failures)
	get_tree().quit(1 if _failures else 0)

func _begin(name: String) -> void:
	print("crowdbake-check: begin " + name)

func _end(name: String, why := "") -> void:
	if not why.is_empty():
		_failures += 1
		print("crowdbake-check: fail %s | %s" % [name, why])
	print("crowdbake-check: end " + name)

func _run() -> void:
	_begin("loader parses")
	_loader_script = load(SHIPPED + "/crowdbake_loader.gd")
	_end("loader parses", "" if _loader_script and _loader_script.can_instantiate() else "crowdbake_loader.gd did not compile")
	if not _loader_script:
		return
	for bake in _bakes():
		_check_palette(bake)
	_check_refusals()
	for file in DirAccess.get_files_at(SHIPPED):
		if file.begins_with("crowdbake_crowd") and file.ends_with(".gdshader"):
			for layout in 3:
				await _check_shader(file, layout)
	var shipped := FileAccess.get_file_as_string(SHIPPED + "/crowdbake_crowd.gdshader")
	# A GLSL-level error that Godot's own parser accepts: only drawing compiles it.
	await _draw_case("broken: usampler2D without highp", _variant(shipped.replace("#include \"crowdbake_palette.gdshaderinc\"",
			FileAccess.get_file_as_string(SHIPPED + "/crowdbake_palette.gdshaderinc").replace("highp usampler2D", "usampler2D")), 2, 1),
			BAKES + "/qpos-u16.pal")
	await _draw_case("broken: undefined identifier", _variant(shipped.replace("BONE_WEIGHTS, inst", "BONE_WEIGHT, inst"), 2, 1),
			BAKES + "/qpos-u16.pal")
	await _check_herd()
	await _check_custom_data_precision()
	await load(ROOT + "/check_addon.gd").new(self).run()

# The bakes run_godot.mjs was given, NAME.pal with NAME = LAYOUT-PRECISION[-zstd].
func _bakes() -> PackedStringArray:
	var out := PackedStringArray()
	for file in DirAccess.get_files_at(BAKES):
		if file.ends_with(".pal"):
			out.append(file.get_basename())
	return out

func _new_loader() -> RefCounted:
	return _loader_script.new()

# The loader's texture must hold the .pal payload bit for bit, in the format its precision names.
func _check_palette(bake: String) -> void:
	var name := "palette " + bake
	_begin(name)
	var loader := _new_loader()
	var pal: Dictionary = loader.load_palette(BAKES + "/" + bake + ".pal")
	if pal.is_empty():
		return _end(name, "load_palette failed: " + loader.error)
	var parts := bake.split("-")
	var image: Image = pal["image"] # the texture's source: GLES3 cannot read integer textures back
	var expected := _raw_payload(BAKES + "/" + bake.trim_suffix("-zstd") + ".pal")
	var formats := {"float": Image.FORMAT_RGBAF, "half": Image.FORMAT_RGBAH, "u16": Image.FORMAT_RGBA16I}
	var why := ""
	if pal["layout"] != parts[0] or pal["precision"] != parts[1]:
		why = "reports %s/%s" % [pal["layout"], pal["precision"]]
	elif image.get_format() != formats[parts[1]]:
		why = "image format %d, expected %d" % [image.get_format(), formats[parts[1]]]
	elif image.get_data() != expected:
		var got := image.get_data()
		var at := 0
		while at < got.size() and got[at] == expected[at]:
			at += 1
		why = "texture bytes differ from the .pal payload at byte %d of %d (%s vs %s)" % [at, got.size(),
				got.slice(at, at + 8).hex_encode(), expected.slice(at, at + 8).hex_encode()]
	_end(name, why)

# The payload of an uncompressed .pal, read here independently of the loader.
func _raw_payload(path: String) -> PackedByteArray:
	var bytes := FileAccess.get_file_as_bytes(path)
	var offset := bytes.decode_u64(152)
	return bytes.slice(offset, offset + bytes.decode_u64(160))

# Damaged files and mismatched shaders: refused with a message naming the file and the fix, and the
# error goes through push_error (kept in release builds, unlike assert).
func _check_refusals() -> void:
	var good := FileAccess.get_file_as_bytes(BAKES + "/qpos-u16.pal")
	var cases := {
		"truncated": [good.slice(0, good.size() - 100), "truncated"],
		"not a palette": [FileAccess.get_file_as_bytes(SHIPPED + "/crowdbake_loader.gd"), "not a crowdbake palette"],
		"version 8": [_patched_u32(good, 8, 8), "version 8 is not supported"],
		# flag bit 6 (timed rows) in a file of an older version: timed rows are version 7
		"timed rows before version 7": [_patched_u32(_patched_u32(good, 8, 6), 12, good.decode_u32(12) | 64), "flag bit 6 (timed rows)"],
		# version 6 with flag bit 5 (local rows) and no bone range table (header byte 200 left 0)
		"local rows without their bone range table": [_patched_u32(_patched_u32(good, 8, 6), 12, good.decode_u32(12) | 32), "do not add up"],
		"payload offset past the end": [_patched_u32(good, 152, 0x7fffffff), "do not add up"],
	}
	for what in cases:
		var name: String = "expect-error: refuses " + what
		_begin(name)
		var path: String = ROOT + "/damaged.pal"
		var f := FileAccess.open(path, FileAccess.WRITE)
		f.store_buffer(cases[what][0])
		f.close()
		var loader := _new_loader()
		var pal: Dictionary = loader.load_palette(path)
		var ok: bool = pal.is_empty() and loader.error.begins_with(path) and loader.error.contains(cases[what][1])
		_end(name, "" if ok else "loaded, or said '%s'" % loader.error)
	var name := "expect-error: refuses a shader of another layout"
	_begin(name)
	var loader := _new_loader()
	var material := ShaderMaterial.new()
	material.shader = load(SHIPPED + "/crowdbake_crowd.gdshader")
	var ok: bool = not loader.apply_palette(material, loader.load_palette(BAKES + "/mat4-float.pal"), "Herd") \
			and loader.error.contains("set `#define CB_LAYOUT 0` and `#define CB_U16 0`")
	_end(name, "" if ok else "accepted, or said '%s'" % loader.error)

func _patched_u32(bytes: PackedByteArray, at: int, value: int) -> PackedByteArray:
	var out := bytes.duplicate()
	out.encode_u32(at, value)
	return out

# A shipped shader's source with its two defines set.
func _variant(code: String, layout: int, u16: int) -> String:
	var re := RegEx.create_from_string("(?m)^#define CB_LAYOUT \\d+")
	code = re.sub(code, "#define CB_LAYOUT %d" % layout)
	return RegEx.create_from_string("(?m)^#define CB_U16 \\d+").sub(code, "#define CB_U16 %d" % u16)

# A shipped shader with the u16 and the float palette of one layout. Both decode to the same pose
# (the bakes differ by well under a pixel here), so the two drawings must cover the same pixels: a
# wrong u16 decode or upload moves, collapses or loses the triangles.
func _check_shader(file: String, layout: int) -> void:
	var source := FileAccess.get_file_as_string(SHIPPED + "/" + file)
	var masks := {}
	# Half palettes are version 3, their positions relative to each bone's offset: the shader
	# must add the offsets back (and skin about the bind positions), or the drawing moves.
	var precisions := ["float", "u16", "half"]
	for precision in precisions:
		var name := "shader %s %s/%s" % [file, LAYOUTS[layout], precision]
		masks[precision] = await _draw_case(name, _variant(source, layout, 1 if precision == "u16" else 0),
				"%s/%s-%s.pal" % [BAKES, LAYOUTS[layout], precision])
	for precision in precisions.slice(1):
		var name := "%s draws as float: %s %s" % [precision, file, LAYOUTS[layout]]
		_begin(name)
		var differ := 0
		var covered := 0
		for i in masks["float"].size():
			differ += 1 if masks[precision][i] != masks["float"][i] else 0
			covered += masks["float"][i]
		print("crowdbake-check: %d of %d covered pixels differ" % [differ, covered])
		_end(name, "" if covered > 100 and differ * 50 <= covered else "%d of %d covered pixels differ" % [differ, covered])

# Draws a small skinned MultiMesh with `code` and the palette `bake` for two frames (Godot parses
# the shader when its code is set and compiles the GLSL when it first draws); returns the coverage
# mask of the last frame, one byte per pixel.
func _draw_case(name: String, code: String, bake: String) -> PackedByteArray:
	_begin(name)
	_shader_count += 1
	var shader := Shader.new()
	# A path beside the shipped files, so that the relative #include resolves; a new one each time
	# because the previous shader may still hold its path.
	shader.resource_path = SHIPPED + "/check_%d.gdshader" % _shader_count
	shader.code = code
	var material := ShaderMaterial.new()
	material.shader = shader
	var loader := _new_loader()
	var pal: Dictionary = loader.load_palette(bake)
	if pal.is_empty() or not loader.apply_palette(material, pal, name):
		_end(name, loader.error)
		return PackedByteArray()
	_herd.multimesh = _skinned_multimesh()
	_herd.material_override = material
	await RenderingServer.frame_post_draw
	await RenderingServer.frame_post_draw
	var mask := _coverage()
	var drawn := mask.count(1)
	print("crowdbake-check: %d pixels drawn" % drawn)
	_end(name, "" if drawn > 0 or name.begins_with("broken:") else "drew nothing")
	return mask

# Which pixels the herd covered in the last frame (the background is transparent).
func _coverage() -> PackedByteArray:
	var image := _viewport.get_texture().get_image()
	var mask := PackedByteArray()
	for y in image.get_height():
		for x in image.get_width():
			mask.append(1 if image.get_pixel(x, y).a > 0.0 else 0)
	return mask

# Two instances of a triangle skinned to four bones, with custom data and colors (crossfade).
func _skinned_multimesh() -> MultiMesh:
	var arrays := []
	arrays.resize(Mesh.ARRAY_MAX)
	arrays[Mesh.ARRAY_VERTEX] = PackedVector3Array([Vector3(-1, -1, 0), Vector3(0, 1, 0), Vector3(1, -1, 0)])
	arrays[Mesh.ARRAY_NORMAL] = PackedVector3Array([Vector3.BACK, Vector3.BACK, Vector3.BACK])
	arrays[Mesh.ARRAY_TANGENT] = PackedFloat32Array([1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1])
	arrays[Mesh.ARRAY_BONES] = PackedInt32Array([2, 14, 0, 0, 20, 30, 0, 0, 38, 0, 0, 0])
	arrays[Mesh.ARRAY_WEIGHTS] = PackedFloat32Array([0.5, 0.5, 0, 0, 0.25, 0.75, 0, 0, 1, 0, 0, 0])
	var mesh := ArrayMesh.new()
	mesh.add_surface_from_arrays(Mesh.PRIMITIVE_TRIANGLES, arrays)
	var mm := MultiMesh.new()
	mm.transform_format = MultiMesh.TRANSFORM_3D
	mm.use_custom_data = true
	mm.use_colors = true
	mm.mesh = mesh
	mm.instance_count = 2
	for i in 2:
		mm.set_instance_transform(i, Transform3D(Basis(), Vector3(i - 0.5, 0, 0)))
		# Rate 0: a fixed pose between two rows whatever TIME is, so drawings can be compared.
		mm.set_instance_custom_data(i, Color(60 + 90 * i, 24, 0, 0.37))
		mm.set_instance_color(i, Color(30, 24, 0, 0.5))
	return mm

# fill_herd from the roster manifest: the instances carry the manifest's numbers.
func _check_herd() -> void:
	var name := "fill_herd from roster.json"
	_begin(name)
	var loader := _new_loader()
	if not loader.load_roster(BAKES + "/roster/roster.json"):
		return _end(name, loader.error)
	var herd := MultiMeshInstance3D.new()
	herd.multimesh = _skinned_multimesh()
	herd.material_override = ShaderMaterial.new()
	herd.material_override.shader = load(SHIPPED + "/crowdbake_crowd.gdshader")
	_viewport.add_child(herd)
	if not loader.fill_herd(herd, "goat", "wander", 1.4, 50, 10.0):
		return _end(name, loader.error)
	var want: Dictionary = loader.roster["types"]["goat"]["states"]["wander"]["instance"]
	var got := herd.multimesh.get_instance_custom_data(3)
	await RenderingServer.frame_post_draw
	var why := ""
	if herd.multimesh.instance_count != 50:
		why = "%d instances" % herd.multimesh.instance_count
	elif got.r != want["first_row"] or got.g != want["frame_count"]:
		why = "instance 3 has first row %s and %s frames; the manifest says %s and %s" % [got.r, got.g,
				want["first_row"], want["frame_count"]]
	_end(name, why)
	name = "expect-error: fill_herd refuses rows the Compatibility renderer cannot address"
	_begin(name)
	loader.roster["types"]["goat"]["states"]["wander"]["instance"]["first_row"] = 3001
	var refused: bool = not loader.fill_herd(herd, "goat", "wander", 1.4, 5, 10.0) \
			and loader.error.contains("exact only up to row 2048")
	_end(name, "" if refused else "accepted, or said '%s'" % loader.error)
	herd.queue_free()

# The premise of that refusal: the renderer this test runs (Compatibility) rounds custom data to
# half floats, so 3001 reaches the shader as 3000. If a Godot release stores floats, this fails and
# the loader's limit can go.
func _check_custom_data_precision() -> void:
	var name := "Compatibility renderer rounds INSTANCE_CUSTOM to half floats"
	_begin(name)
	var shader := Shader.new()
	shader.code = "shader_type spatial;\nrender_mode unshaded, cull_disabled;\nvarying float row;\n" \
			+ "void vertex() { row = INSTANCE_CUSTOM.x; }\n" \
			+ "void fragment() { ALBEDO = vec3(row == 3001.0 ? 1.0 : 0.0, row == 3000.0 ? 1.0 : 0.0, 0.0); }\n"
	var quad := QuadMesh.new()
	quad.size = Vector2(4, 4)
	var mm := MultiMesh.new()
	mm.transform_format = MultiMesh.TRANSFORM_3D
	mm.use_custom_data = true
	mm.mesh = quad
	mm.instance_count = 1
	mm.set_instance_transform(0, Transform3D())
	mm.set_instance_custom_data(0, Color(3001, 0, 0, 0))
	_herd.multimesh = mm
	_herd.material_override = ShaderMaterial.new()
	_herd.material_override.shader = shader
	await RenderingServer.frame_post_draw
	await RenderingServer.frame_post_draw
	var pixel := _viewport.get_texture().get_image().get_pixel(32, 32)
	var why := ""
	if RenderingServer.get_current_rendering_method() != "gl_compatibility":
		why = "renderer is " + RenderingServer.get_current_rendering_method()
	elif pixel.g < 0.5 or pixel.r > 0.5:
		why = "custom data 3001 read as %s (red: 3001, green: 3000)" % pixel
	_end(name, why)
