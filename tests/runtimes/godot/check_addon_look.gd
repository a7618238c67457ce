# check_addon_look.gd - the addon's look, sockets, demo and import in Godot 4.6's web build, run by
# check_addon.gd (whose viewport, camera, herds and case lines it uses): the herd against Godot's own
# skinned import of Cow.glb and Husky.glb in colour, Cow's sockets at a prop's own size, the demo scene's herd, and
# what the editor's .pal and roster.json importers save (their own _import, run on copies extending RefCounted)
# loading back whole.
extends RefCounted

const ROOT := "/crowdbake"
const ADDON := ROOT + "/addons/crowdbake"
const COW := ROOT + "/bakes/cow"
const HUSKY := ROOT + "/bakes/husky"
const WALK := "AnimalArmature|Walk"
const SIZE := 0.1

var addon # check_addon.gd's instance

func _init(addon_check) -> void:
	addon = addon_check

# Cow's own sockets (the manifest's, Head_end among them): Cow's armature is at scale 100, yet a prop
# hung on socket_transform keeps its own size: the socket's axes are as long as the instance's scale.
func check_socket_scale(roster, mesh: Mesh) -> void:
	var name := "socket_transform keeps a prop's own size on Cow (armature at scale 100)"
	addon._begin(name)
	roster.types["cow"]["sockets"] = load(ADDON + "/crowdbake_roster.gd")._sockets(addon._manifest["types"]["cow"]["sockets"])
	var herd: MultiMeshInstance3D = addon._new_herd(roster, mesh, 1)
	herd.advance(0.4)
	var worst := 0.0
	for socket in roster.types["cow"]["sockets"]:
		var scale: Vector3 = herd.socket_transform(0, socket).basis.get_scale()
		worst = maxf(worst, maxf(absf(scale.x / SIZE - 1.0), maxf(absf(scale.y / SIZE - 1.0), absf(scale.z / SIZE - 1.0))))
	herd.queue_free()
	print("crowdbake-check: %d sockets, axes within %s of the instance's scale" % [roster.types["cow"]["sockets"].size(), worst])
	var listed: int = addon._manifest["types"]["cow"]["sockets"].size()
	addon._end(name, "" if worst < 1e-3 and listed > 0 and roster.types["cow"]["sockets"].size() == listed else "axes off by %s" % worst)

# The largest difference of two colours' channels, relative to the second's brightest channel.
static func _colour_distance(c: Color, reference: Color) -> float:
	var d := maxf(absf(c.r - reference.r), maxf(absf(c.g - reference.g), absf(c.b - reference.b)))
	return d / maxf(maxf(reference.r, maxf(reference.g, reference.b)), 1e-6)

# Covered pixels whose colour differs by more than 12/255 in a channel (what the three.js look test
# counts), those covered in either image, and those covered in only one (the silhouette's part).
static func _colour_differ(a: Image, b: Image) -> Array:
	var n := 0
	var covered := 0
	var edge := 0
	for y in a.get_height():
		for x in a.get_width():
			var p := a.get_pixel(x, y)
			var q := b.get_pixel(x, y)
			if p.a == 0.0 and q.a == 0.0:
				continue
			covered += 1
			edge += 1 if (p.a == 0.0) != (q.a == 0.0) else 0
			n += 1 if maxf(absf(p.r - q.r), maxf(absf(p.g - q.g), maxf(absf(p.b - q.b), absf(p.a - q.a)))) > 12.0 / 255.0 else 0
	return [n, covered, edge]

# The herd keeps the model's look: its plain-colour surfaces (one glTF material each) merged into one
# draw call, drawn in colour like Godot's own import of the same .glb (Skeleton3D + AnimationPlayer,
# StandardMaterial3D from the glTF's materials) at the same clip time, lit from the camera's side so
# that colours show. The negative control: the whole mesh in one colour (the addon's old look).
# `surfaces`: how many surfaces the model has (all plain colours on Quaternius' animals).
func check_look(type: String, glb: String, roster_path: String, surfaces: int) -> void:
	var name := "the herd looks like Godot's own skinned %s: %d materials in one draw call" % [glb.get_file(), surfaces]
	addon._begin(name)
	var doc := GLTFDocument.new()
	var state := GLTFState.new()
	doc.append_from_file(glb, state)
	var scene: Node3D = doc.generate_scene(state)
	var mesh: Mesh = addon._herd_script.skinned_mesh_in(scene)
	var roster = ResourceLoader.load(roster_path, "CrowdbakeRoster")
	var players := scene.find_children("*", "AnimationPlayer", true, false)
	var herd: MultiMeshInstance3D = addon._herd_script.new()
	herd.playing = false
	addon._viewport.add_child(herd)
	if mesh == null or roster == null or not herd.setup(roster, type, mesh, 1):
		scene.free()
		herd.queue_free()
		return addon._end(name, "no mesh, roster or herd: %s" % herd.error)
	# About a unit tall, side on, filling the view.
	var bounds: AABB = herd.palette.largest_bounds()
	var xform := Transform3D(Basis(Vector3.UP, PI / 2).scaled(Vector3.ONE / bounds.size.y), Vector3.ZERO)
	var box := xform * bounds
	addon._camera.transform = Transform3D(Basis(), box.get_center() + Vector3(0, 0, 0.75 * maxf(box.size.x, box.size.y)))
	var light: DirectionalLight3D = addon._viewport.find_children("*", "DirectionalLight3D", true, false)[0]
	var side_light := light.transform
	light.transform = Transform3D(Basis.looking_at(Vector3(-0.4, -0.6, -1).normalized(), Vector3.UP), Vector3.ZERO)
	addon._viewport.size = Vector2i(128, 128) # colours need more than a silhouette's pixels
	herd.place(0, xform)
	var clip_name: String = roster.types[type]["states"]["wander"]["clip"]
	herd.set_state(0, "wander", 0.0)
	herd.advance(0.5)
	var inst: Vector4 = herd.instance_numbers(0)
	var clip: Dictionary = roster.types[type]["clips"][clip_name]
	var seconds: float = fposmod(herd.time * inst.z + inst.w * absf(inst.y), absf(inst.y)) / float(clip["fps"])
	var drawn: Image = await addon._frame()
	var calls: int = addon._viewport.get_render_info(Viewport.RENDER_INFO_TYPE_VISIBLE, Viewport.RENDER_INFO_DRAW_CALLS_IN_FRAME)
	var herd_mesh := herd.multimesh.mesh
	herd.multimesh.mesh = mesh # the old look: the model's surfaces in one material
	var one_colour: ShaderMaterial = herd.materials[0].duplicate()
	one_colour.set_shader_parameter("albedo", Color(0.85, 0.78, 0.66))
	herd.material_override = one_colour
	var old_look: Image = await addon._frame()
	herd.multimesh.mesh = herd_mesh
	herd.material_override = null
	herd.visible = false
	scene.transform = xform
	addon._viewport.add_child(scene)
	if not players.is_empty():
		players[0].play(clip_name)
		players[0].seek(seconds, true)
		players[0].pause()
	var reference: Image = await addon._frame()
	var reference_calls: int = addon._viewport.get_render_info(Viewport.RENDER_INFO_TYPE_VISIBLE, Viewport.RENDER_INFO_DRAW_CALLS_IN_FRAME)
	scene.queue_free()
	herd.queue_free()
	light.transform = side_light
	addon._viewport.size = Vector2i(64, 64)
	var look := _colour_differ(drawn, reference)
	var old := _colour_differ(old_look, reference)
	var share := float(look[0]) / maxf(look[1], 1)
	var old_share := float(old[0]) / maxf(old[1], 1)
	# The mean colour of the covered pixels, which a pixel's worth of silhouette does not move.
	var mean_herd: Color = addon._covered(drawn)[0]
	var mean_reference: Color = addon._covered(reference)[0]
	var mean_old: Color = addon._covered(old_look)[0]
	var off := _colour_distance(mean_herd, mean_reference)
	var off_old := _colour_distance(mean_old, mean_reference)
	print("crowdbake-check: %s at %.3f s: %d covered pixels, %.2f%% differ in colour by more than 12/255 from Godot's own skinning (%d of them covered in one image only; one colour: %.1f%%); mean colour %s against %s: off by %.2f%% (one colour %s: %.1f%%); %d surfaces merged, %d draw calls a frame (shadow pass included), Godot's import %d"
			% [glb.get_file(), seconds, look[1], 100 * share, look[2], 100 * old_share, mean_herd, mean_reference, 100 * off, mean_old,
			100 * off_old, herd.surfaces_merged, calls, reference_calls])
	var why := ""
	if players.is_empty():
		why = "no AnimationPlayer in Godot's import"
	# Godot's colours, where one colour is far off; the silhouettes differ by the palette's sampling of the clip
	# (30 rows a second, linear between them) against Godot's own keys, a pixel here and there.
	elif look[1] < 1000 or share > 0.02 or off > 0.02 or old_share < 0.3:
		why = "see the numbers above"
	elif herd.surfaces_merged != surfaces or calls * 4 > reference_calls:
		why = "%d surfaces merged, %d draw calls" % [herd.surfaces_merged, calls]
	addon._end(name, why)


# The demo's script (demo/crowdbake_demo.gd) on its own model and roster, which make bakes into
# demo/herd/ (the project's generated quadruped): it opens to a herd, drawn.
func check_demo() -> void:
	var name := "the demo opens to a herd: its own model and roster"
	addon._begin(name)
	var demo: Node3D = load(ADDON + "/demo/crowdbake_demo.gd").new()
	demo.roster_path = ADDON + "/demo/herd/roster.json"
	demo.model_path = ADDON + "/demo/herd/quadruped.glb"
	demo.animals = 16 # a smaller field than the scene's 64: SwiftShader draws it on the CPU
	var herd: MultiMeshInstance3D = load(ADDON + "/crowdbake_herd.gd").new()
	herd.name = "Herd"
	demo.add_child(herd)
	addon._viewport.add_child(demo) # _ready builds the herd
	addon._camera.transform = Transform3D(Basis(), Vector3(0, 8, 20)).looking_at(Vector3.ZERO)
	var image: Image = await addon._frame()
	var covered: Array = addon._covered(image)
	print("crowdbake-check: the demo's herd: %d animals of type '%s', %d pixels drawn" % [herd.count, demo.animal, covered[1]])
	var why := "" if herd.palette != null and herd.count == demo.animals and covered[1] > 20 else "see the numbers above"
	demo.queue_free()
	addon._end(name, why)

# The editor's importer `script` (crowdbake_import_palette.gd or crowdbake_import_roster.gd) as the web
# build can run it: EditorImportPlugin is an editor class that the export does not have, so the
# importer and its base (crowdbake_import_base.gd) are copied to user:// reading "extends RefCounted",
# their preloads pointed at the addon. What its _import does (read, refuse, save) is the shipped code.
func _importer(script: String) -> Object:
	DirAccess.make_dir_recursive_absolute("user://importers")
	for file in ["crowdbake_import_base.gd", script]:
		var text := FileAccess.get_file_as_string(ADDON + "/" + file)
		text = text.replace("extends EditorImportPlugin", "extends RefCounted").replace("preload(\"", "preload(\"%s/" % ADDON)
		var out := FileAccess.open("user://importers/" + file, FileAccess.WRITE)
		out.store_string(text)
		out.close()
	return load("user://importers/" + script).new()

# What the importer `script` saves of `source` (its _import, called as the editor calls it, saving to
# `saved` + its extension), loaded back; or why not, a String.
func _import_with(script: String, source: String, saved: String) -> Variant:
	var none: Array[String] = []
	var importer = _importer(script)
	var err: int = importer._import(source, saved, {}, none, none)
	if err != OK:
		return "%s: the import failed (%s)" % [script, error_string(err)]
	var back = ResourceLoader.load(saved + ".res", "", ResourceLoader.CACHE_MODE_IGNORE)
	return back if back != null else "%s: what it saved did not load back" % script

# The editor's .pal import (crowdbake_import_palette.gd: CrowdbakePalette.load_file, then
# ResourceSaver.save) and what load() of the imported palette then gives: every bone matrix of every
# clip as the palette read from the file gives it, and the same texture.
func check_imported_palette() -> void:
	var name := "a palette saved as a resource (the .pal import) loads back whole"
	addon._begin(name)
	var palette = load(ADDON + "/crowdbake_palette.gd").new()
	var why := "" if palette.load_file(COW + "/qpos-u16.pal") else str(palette.error)
	var back = null
	if why.is_empty():
		back = _import_with("crowdbake_import_palette.gd", COW + "/qpos-u16.pal", "user://crowdbake_imported_palette")
	if back is String:
		why = back
	var worst := 0.0
	var compared := 0
	if why.is_empty():
		for clip in palette.clips:
			for bone in palette.bone_names.size():
				var m1: Transform3D = palette.bone_matrix(clip["name"], 0.37, bone)
				var m2: Transform3D = back.bone_matrix(clip["name"], 0.37, bone)
				worst = maxf(worst, (m1.origin - m2.origin).length() + (m1.basis.x - m2.basis.x).length())
				compared += 1
		if back.texture == null or back.texture.get_image().get_data() != palette.texture.get_image().get_data():
			why = "the texture differs"
		elif compared == 0 or worst > 0.0:
			why = "%d matrices compared, off by up to %s" % [compared, worst]
	print("crowdbake-check: the palette crowdbake_import_palette.gd saved: %d bone matrices compared, off by %s" % [compared, worst])
	addon._end(name, why)

# The editor's roster.json import (crowdbake_import_roster.gd: CrowdbakeRoster.import_file, then
# ResourceSaver.save) and what load() of the imported roster then gives: Cow's types, states,
# clips and sockets as the manifest has them, its palette resolved and whole (the same texture), a herd
# set up from it drawing the same bone matrices as a herd of the roster read at run time (afresh: the
# other checks change the one they share); any other
# JSON (the conformance cases' cases.json) imported as the JSON Godot's own loader gives; a file
# that is not JSON refused with a line naming it.
func check_imported_roster(mesh: Mesh) -> void:
	var name := "a roster.json saved as a resource (the roster import) loads back with its palette, and a herd takes it"
	addon._begin(name)
	var roster = ResourceLoader.load(COW + "/roster/roster.json", "CrowdbakeRoster", ResourceLoader.CACHE_MODE_IGNORE)
	var back = _import_with("crowdbake_import_roster.gd", COW + "/roster/roster.json", "user://crowdbake_imported_roster")
	var why: String = back if back is String else ""
	if why.is_empty() and (back.get_script() == null or back.get("types") == null or back.types.keys() != roster.types.keys()):
		why = "it did not load back as a roster: %s" % back
	if not why.is_empty():
		back = null
	var worst := 0.0
	if why.is_empty():
		var cow: Dictionary = back.types["cow"]
		var want: Dictionary = roster.types["cow"]
		for key in ["states", "clips", "sockets", "default_state", "speed_reference"]:
			if cow[key] != want[key]:
				why += "%s differ; " % key
		if cow["palette"] == null or cow["palette"].texture.get_image().get_data() != want["palette"].texture.get_image().get_data():
			why += "the palette's texture differs; "
		var herds: Array[MultiMeshInstance3D] = []
		for r in [roster, back]:
			var herd: MultiMeshInstance3D = addon._herd_script.new()
			herd.playing = false
			if not herd.setup(r, "cow", mesh, 2):
				why += "setup failed: %s; " % herd.error
			herd.advance(0.7)
			herds.append(herd)
		for bone in want["palette"].bone_names.size():
			var a: Transform3D = herds[0].bone_transform_at(1, bone)
			var b: Transform3D = herds[1].bone_transform_at(1, bone)
			worst = maxf(worst, (a.origin - b.origin).length() + (a.basis.x - b.basis.x).length() + (a.basis.y - b.basis.y).length())
		for herd in herds:
			herd.free()
		if worst > 0.0:
			why += "the herds' bone matrices differ by %s" % worst
	var other := _imported_other_json()
	print("crowdbake-check: the roster crowdbake_import_roster.gd saved: types %s, herd bone matrices off by %s; %s"
			% [back.types.keys() if back else [], worst, other if not other.is_empty() else "other JSON imported as JSON, a broken file refused"])
	addon._end(name, why + other)

# Any other JSON imports as Godot's own JSON resource (its data whole after the import's save and a
# load), and a file that is not JSON is refused with a line naming it (by the roster's reader: the
# importer would log the line as an error). "" when both hold, else what failed.
func _imported_other_json() -> String:
	var importer := load(ADDON + "/crowdbake_roster.gd")
	var cases := ROOT + "/bakes/conformance/cases.json"
	var back = _import_with("crowdbake_import_roster.gd", cases, "user://crowdbake_imported_json")
	if not back is JSON:
		return "cases.json did not import as JSON: %s" % back
	if back.data != JSON.parse_string(FileAccess.get_file_as_string(cases)):
		return "cases.json's data did not load back whole"
	var bad := "user://crowdbake_not_json.json"
	FileAccess.open(bad, FileAccess.WRITE).store_string("{\"schema\": \"crowdbake-roster/1\",")
	var refused = importer.new().import_file(bad)
	return "" if refused is String and refused.begins_with(bad + ":") else "a broken .json gave %s" % refused

# The animation LOD (CrowdbakeHerd.lod): a far instance draws as crowdbake mesh --max-influences 1 wrote
# Cow's mesh (Cow_inf1.glb, its largest weight alone), read by Godot's own importer and drawn with the LOD
# off; a near one, or the LOD off, draws every influence. Compared pixel for pixel in the grazing pose.
func check_lod(roster, mesh: Mesh) -> void:
	var name := "animation LOD: a far instance draws as crowdbake mesh --max-influences 1's mesh, a near one every influence"
	addon._begin(name)
	var doc := GLTFDocument.new()
	var state := GLTFState.new()
	doc.append_from_file(COW + "/Cow_inf1.glb", state)
	var scene: Node = doc.generate_scene(state)
	var one: Mesh = addon._herd_script.skinned_mesh_in(scene) if scene else null
	if scene:
		scene.free()
	if one == null:
		return addon._end(name, "Cow_inf1.glb has no skinned mesh")
	addon._viewport.size = Vector2i(128, 128)
	var near := await _grazing(roster, mesh, Vector2(24, 12), 1.0) # about 110 pixels long: every influence
	var all := await _grazing(roster, mesh, Vector2.ZERO, 1.0)
	var forced := await _grazing(roster, mesh, Vector2(1e9, 1e9), 1.0) # every instance far: one influence
	var written := await _grazing(roster, one, Vector2.ZERO, 1.0)
	var far := await _grazing(roster, mesh, Vector2(24, 12), 0.09) # about 10 pixels long: one influence
	var far_written := await _grazing(roster, one, Vector2.ZERO, 0.09)
	var near_auto := await _grazing(roster, mesh, null, 1.0) # lod_auto, the default: the bake's thresholds
	var far_auto := await _grazing(roster, mesh, null, 0.09)
	addon._viewport.size = Vector2i(64, 64)
	var numbers := [addon._differ(near, all), addon._differ(forced, written), addon._differ(forced, all),
			addon._differ(far, far_written), addon._covered(far)[1], addon._differ(near_auto, all),
			addon._differ(far_auto, far_written)]
	print("crowdbake-check: pixels that differ: near (lod 24, 12) / every influence %d; one influence / the 1-influence mesh %d; one influence / every influence %d; far (lod 24, 12, %d pixels covered) / the 1-influence mesh %d; lod_auto near / every influence %d, far / the 1-influence mesh %d"
			% [numbers[0], numbers[1], numbers[2], numbers[4], numbers[3], numbers[5], numbers[6]])
	var ok: bool = numbers[0] == 0 and numbers[1] == 0 and numbers[2] > 0 and numbers[3] == 0 and numbers[4] > 10
	ok = ok and numbers[5] == 0 and numbers[6] == 0
	addon._end(name, "" if ok else "see the numbers above")
	_check_lod_auto(roster, mesh)

# lod_auto takes the thresholds from the roster's animation_lod (the bake's measure of each tier's
# worst vertex, model units): S / e pixels for an animal S units long; setting lod overrides it.
func _check_lod_auto(roster, mesh: Mesh) -> void:
	var name := "animation LOD: lod_auto's thresholds are the bake's animation_lod at one pixel; setting lod overrides them"
	addon._begin(name)
	var herd: MultiMeshInstance3D = addon._herd_script.new()
	addon._viewport.add_child(herd)
	herd.setup(roster, "cow", mesh, 1)
	var measured: Dictionary = roster.types["cow"]["animation_lod"]
	var size: float = herd.palette.largest_bounds().get_longest_axis_size()
	var want := Vector2(size / float(measured["two_influences_error"]), size / float(measured["one_influence_error"]))
	var auto_lod: Vector2 = herd.lod
	var auto_on: bool = herd.lod_auto
	print("crowdbake-check: %s" % herd.lod_reason)
	herd.lod = Vector2(30, 10)
	var given_off: bool = not herd.lod_auto and herd.lod == Vector2(30, 10) and herd.lod_reason.contains("as given")
	herd.lod_auto = true
	var back: bool = herd.lod.is_equal_approx(want)
	herd.queue_free()
	var why := ""
	if not auto_on or not auto_lod.is_equal_approx(want):
		why = "lod_auto gave %s, the roster's animation_lod %s" % [auto_lod, want]
	elif not (want.x > want.y and want.y > 12.0 and want.x < 100.0):
		why = "thresholds %s out of the range the web runtime measures for Cow (~39, ~21 pixels)" % [want]
	elif not given_off or not back:
		why = "setting lod did not override lod_auto, or lod_auto = true did not restore it"
	addon._end(name, why)

# The bone pass's far tier as a game meets it: two grazing Cows (bone_pass "always") drawn through the build that
# reads each instance's tier while they are near, through the far-only build once both are under halves_pixels()
# tall, and through its 1-influence build once both are in the animation LOD's 1-influence tier too; those builds are
# the programs the herd drew once at setup (_warm_far_builds: no compile at the first switch, mid-game), retired after
# that frame, and each draws the pixels the build that reads each instance's tier (and counts each vertex's
# influences) draws for those instances.
func check_far_tier(roster, mesh: Mesh) -> void:
	var name := "bone pass far tier: the far-only builds, drawn once at setup, while every instance is far (and in the 1-influence tier); the same pixels as the per-instance build"
	addon._begin(name)
	addon._viewport.size = Vector2i(128, 128)
	var herd: MultiMeshInstance3D = addon._herd_script.new()
	herd.playing = false
	herd.bone_pass = "always"
	addon._viewport.add_child(herd)
	herd.setup(roster, "cow", mesh, 2)
	var warm_shaders: Array = herd._warm_ups.map(func(w): return w.material_override.shader if w.is_inside_tree() else null)
	var warmed: bool = warm_shaders == [herd._far_shader, herd._far_one_shader]
	herd.lod = Vector2(2, 1) # every influence over 2 pixels tall: the far tier alone
	var bounds: AABB = herd.palette.largest_bounds()
	var unit_tall := Basis(Vector3.UP, PI / 2).scaled(Vector3.ONE / bounds.size.y)
	for i in 2:
		herd.place(i, Transform3D(unit_tall, Vector3(0.6 * i - 0.3, 0, 0) - unit_tall * bounds.get_center()))
		herd.set_state(i, "graze", 0.0)
	herd.advance(2.5)
	addon._camera.transform = Transform3D(Basis(), Vector3(0, 0, 1.5))
	await addon._frame()
	var near: bool = not herd._far_only and herd.materials[0].shader == herd._mixed_shader
	var retired: bool = herd._warm_ups.is_empty()
	addon._camera.transform = Transform3D(Basis(), Vector3(0, 0, 6))
	var far: Image = await addon._frame()
	var far_only: bool = herd._far_only and not herd._one_only and herd.materials[0].shader == herd._far_shader
	herd._set_far_only(false) # the build that reads each instance's tier, both still marked far
	var per_instance: Image = await addon._frame()
	herd.lod = Vector2(1e9, 1e9) # every instance in the 1-influence tier, as a herd seen from afar
	var one: Image = await addon._frame()
	var one_only: bool = herd._far_only and herd._one_only and herd.materials[0].shader == herd._far_one_shader
	herd._set_far_only(false) # the build that counts each vertex's influences (1 at every vertex in this tier)
	var one_counted: Image = await addon._frame()
	var halves_pixels: float = herd.halves_pixels()
	herd.queue_free()
	addon._viewport.size = Vector2i(64, 64)
	var covered: int = addon._covered(far)[1]
	var differ: int = addon._differ(far, per_instance)
	var one_covered: int = addon._covered(one)[1]
	var one_differ: int = addon._differ(one, one_counted)
	print("crowdbake-check: far tier: warmed at setup %s, retired after a frame %s, near %s, far-only %s, 1-influence %s; %d pixels covered far, %d differ from the per-instance build; %d covered in the 1-influence tier, %d differ from the per-instance build (halves_pixels %.1f)"
			% [warmed, retired, near, far_only, one_only, covered, differ, one_covered, one_differ, halves_pixels])
	var ok := warmed and retired and near and far_only and one_only and covered > 40 and differ == 0
	addon._end(name, "" if ok and one_covered > 40 and one_differ == 0 else "see the numbers above")

# A frame of one Cow grazing (2.5 s in), side on and `scale` units tall, at the camera's place for a
# unit-tall Cow filling the view; lod null: the herd's default (lod_auto).
func _grazing(roster, mesh: Mesh, lod, scale: float) -> Image: # lod null: lod_auto
	var herd: MultiMeshInstance3D = addon._herd_script.new()
	herd.playing = false
	addon._viewport.add_child(herd)
	herd.setup(roster, "cow", mesh, 1)
	if lod != null:
		herd.lod = lod
	var bounds: AABB = herd.palette.largest_bounds()
	var xform := Transform3D(Basis(Vector3.UP, PI / 2).scaled(Vector3.ONE / bounds.size.y), Vector3.ZERO)
	var box := xform * bounds
	addon._camera.transform = Transform3D(Basis(), box.get_center() + Vector3(0, 0, 0.75 * maxf(box.size.x, box.size.y)))
	herd.place(0, Transform3D(xform.basis.scaled(Vector3.ONE * scale), xform.origin + box.get_center() * (1.0 - scale)))
	herd.set_state(0, "graze", 0.0)
	herd.advance(2.5)
	var image: Image = await addon._frame()
	herd.queue_free()
	return image
