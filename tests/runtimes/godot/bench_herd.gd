# bench_herd.gd - frame times of CrowdbakeHerd in Godot 4.6's web build (run_godot.mjs with this script in place of
# check.gd; bench/godot_crowd.py drives it): the same herd of Cows drawn per vertex (bone_pass "never"), through the
# bone pass ("always") and from a VAT of the same frames (the herd's shader with its
# skinning replaced by two texel fetches a vertex, a bench-only variant: the addon has no VAT path). Every instance
# walks; each method draws blocks of frames in turns (so the machine's load hits all alike) into a 240x135
# SubViewport (SwiftShader takes seconds a frame for 1,000 Cows: few frames), and a frame's time is the interval between two frame_post_draw signals
# (and, marked around each block's measured frames, the CPU seconds the browser used: run_godot.mjs). Prints one JSON line:
#   crowdbake-bench: {"counts": {"N": {"METHOD_ms": median, "auto_bone_pass": what "auto" takes, ...}}, "bytes_per_instance": {...}}
extends Node

const ROOT := "/crowdbake"
const ADDON := ROOT + "/addons/crowdbake"
const IN := ROOT + "/bakes"
const BLOCK := 4 # frames a block; the first of each is left out (the switch)
const ROUNDS := 2

var _viewport: SubViewport
var _herd_script: GDScript

func _ready() -> void:
	print("crowdbake-check: begin bench")
	_herd_script = load(ADDON + "/crowdbake_herd.gd")
	ResourceLoader.add_resource_format_loader(load(ADDON + "/crowdbake_format_loader.gd").new()) # no class cache here
	var params: Dictionary = JSON.parse_string(FileAccess.get_file_as_string(IN + "/bench.json"))
	_viewport = SubViewport.new()
	_viewport.size = Vector2i(240, 135)
	_viewport.render_target_update_mode = SubViewport.UPDATE_ALWAYS
	_viewport.own_world_3d = true
	add_child(_viewport)
	var light := DirectionalLight3D.new()
	light.rotation = Vector3(-0.8, 0.5, 0.0)
	_viewport.add_child(light)
	var doc := GLTFDocument.new()
	var state := GLTFState.new()
	doc.append_from_file(IN + "/model.glb", state)
	var mesh: Mesh = _herd_script.skinned_mesh_in(doc.generate_scene(state))
	var roster = ResourceLoader.load(IN + "/roster/roster.json", "CrowdbakeRoster")
	var result := {"counts": {}, "bytes_per_instance": {}}
	for n in params["counts"]:
		var herds := {}
		for method in params["methods"]:
			herds[method] = _herd(roster, params["animal"], mesh, int(n), method)
		var times := {}
		for method in herds:
			times[method] = []
		for r in ROUNDS:
			for method in herds:
				_viewport.add_child(herds[method])
				var last := 0
				for f in BLOCK:
					await RenderingServer.frame_post_draw
					var now := Time.get_ticks_usec()
					if f >= 1:
						times[method].append((now - last) / 1000.0)
					last = now
					if f == 0 or f == BLOCK - 1: # run_godot.mjs counts the browser's CPU seconds between the two
						print("crowdbake-bench-mark: %d %s %s" % [n, method, "begin" if f == 0 else "end"])
				_viewport.remove_child(herds[method])
		var c := {}
		var auto: MultiMeshInstance3D = _herd(roster, params["animal"], mesh, int(n), "auto") # what "auto" takes, and why
		c["auto_reason"] = auto.bone_pass_reason
		c["auto_bone_pass"] = auto.uses_bone_pass
		auto.free()
		if herds.has("bones") and "_far_only" in herds["bones"]: # every instance in the far tier: the far-only build drew
			c["bones_far_only"] = herds["bones"]._far_only
		if herds.has("bones") and "_one_only" in herds["bones"]: # and in the 1-influence tier: its 1-influence build
			c["bones_one_only"] = herds["bones"]._one_only
		for method in herds:
			var t: Array = times[method]
			t.sort()
			c[method + "_ms"] = t[t.size() / 2]
			result["bytes_per_instance"][method] = herds[method].bytes_per_instance()
			herds[method].free()
		result["counts"][str(n)] = c
		print("crowdbake-bench-progress: %s" % JSON.stringify(c))
	result["bones"] = roster.types[params["animal"]]["palette"].bone_names.size()
	result["vertices"] = range(mesh.get_surface_count()).reduce(func(a, s): return a + mesh.surface_get_array_len(s), 0)
	print("crowdbake-bench: " + JSON.stringify(result))
	print("crowdbake-check: end bench")
	print("crowdbake-check: done, 0 failed")
	get_tree().quit(0)

# A herd of n walking animals on a grid, the camera over it all; method: "palette", "bones", "auto" or "vat".
func _herd(roster, animal: String, mesh: Mesh, n: int, method: String) -> MultiMeshInstance3D:
	var herd: MultiMeshInstance3D = _herd_script.new()
	herd.bone_pass = {"palette": "never", "bones": "always", "auto": "auto", "vat": "never"}[method]
	if not herd.setup(roster, animal, mesh, n):
		push_error(herd.error)
	var size: float = herd.palette.largest_bounds().get_longest_axis_size()
	var side := ceili(sqrt(n))
	for i in n:
		herd.place(i, Transform3D(Basis(), Vector3((i % side - side * 0.5) * size, 0.0, (i / side - side * 0.5) * size)))
	if method == "vat":
		_use_vat(herd)
	var camera := Camera3D.new()
	camera.far = side * size * 10.0
	camera.look_at_from_position(Vector3(0.0, side * size * 0.8, side * size * 0.9), Vector3.ZERO)
	camera.current = true
	herd.add_child(camera)
	return herd

# The herd's shader with its skinning replaced by a VAT's (crowdbake vat --like the palette: its frames are the
# palette's rows): positions and normals fetched at the vertex's index in the frame's two rows and blended, as
# runtimes/web/crowdbake_vat.mjs does; cross-fades blend two such.
func _use_vat(herd: MultiMeshInstance3D) -> void:
	var vat: Dictionary = JSON.parse_string(FileAccess.get_file_as_string(IN + "/vat.json"))
	var w: int = vat["width"]
	var h: int = vat["height"]
	var positions := ImageTexture.create_from_image(Image.create_from_data(w, h, false, Image.FORMAT_RGBAH,
			FileAccess.get_file_as_bytes(IN + "/vat_positions.bin")))
	var normals := ImageTexture.create_from_image(Image.create_from_data(w, h, false, Image.FORMAT_RGBAH,
			FileAccess.get_file_as_bytes(IN + "/vat_normals.bin")))
	for m in herd.materials:
		var code: String = m.shader.code
		var call := RegEx.create_from_string("cb_skin_vertex_crossfade_influences\\([^;]*;")
		var at := code.find("void vertex()")
		code = code.substr(0, at) + call.sub(code.substr(at), """vat_skin(inst, VERTEX_ID, p, n);
	t = TANGENT;
	if (fade < 1.0) {
		vec3 p0;
		vec3 n0;
		vat_skin(cb_instance(INSTANCE_ID, 1), VERTEX_ID, p0, n0);
		p = mix(p0, p, fade);
		n = mix(n0, n, fade);
	}""")
		code = code.replace("void vertex() {", """uniform highp sampler2D vat_positions : filter_nearest, repeat_disable;
uniform highp sampler2D vat_normals : filter_nearest, repeat_disable;
uniform int vat_frame_width;
uniform int vat_rows_per_frame;
uniform int vat_rows_per_block;
ivec2 vat_texel(int frame, int vid) {
	int row = frame * vat_rows_per_frame + vid / vat_frame_width;
	int block = row / vat_rows_per_block;
	return ivec2(block * vat_frame_width + vid % vat_frame_width, row - block * vat_rows_per_block);
}
void vat_skin(vec4 inst, int vid, out vec3 p, out vec3 n) {
	int row0;
	int row1;
	float fr;
	cb_frame(inst, herd_time, row0, row1, fr);
	p = mix(texelFetch(vat_positions, vat_texel(row0, vid), 0).xyz, texelFetch(vat_positions, vat_texel(row1, vid), 0).xyz, fr);
	n = mix(texelFetch(vat_normals, vat_texel(row0, vid), 0).xyz, texelFetch(vat_normals, vat_texel(row1, vid), 0).xyz, fr);
}

void vertex() {""")
		var shader := Shader.new()
		shader.code = code
		m.shader = shader
		m.set_shader_parameter("vat_positions", positions)
		m.set_shader_parameter("vat_normals", normals)
		m.set_shader_parameter("vat_frame_width", vat["frameWidth"])
		m.set_shader_parameter("vat_rows_per_frame", vat["rowsPerFrame"])
		m.set_shader_parameter("vat_rows_per_block", h)
