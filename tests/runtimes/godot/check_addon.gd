# check_addon.gd - the addon (runtimes/godot/addons/crowdbake) at runtime in Godot 4.6's web build, on Cow: run last by
# check.gd, whose begin/end lines it prints. Independent numbers: the reference joint matrices of
# ../shared/reference/Cow.fps30.csv, the roster manifest crowdbake wrote, Cow.glb's mesh as Godot's own
# glTF importer reads it, and pixels Godot draws.
extends RefCounted

const ROOT := "/crowdbake"
const ADDON := ROOT + "/addons/crowdbake"
const COW := ROOT + "/bakes/cow"
const WALK := "AnimalArmature|Walk"
const DEATH := "AnimalArmature|Death"
const SIZE := 0.1 # the herd's animals at a tenth of Cow's size (about 1 unit tall)

var check # check.gd's node: _begin, _end
var _herd_script: GDScript
var _reference := {} # clip name -> frame -> [t, [joint matrices, 16 floats column-major]]
var _manifest := {} # roster.json as parsed here
var _viewport: SubViewport
var _camera: Camera3D

func _init(checker) -> void:
	check = checker

func run() -> void:
	_herd_script = load(ADDON + "/crowdbake_herd.gd")
	_read_reference(COW + "/reference.csv")
	_manifest = JSON.parse_string(FileAccess.get_file_as_string(COW + "/roster/roster.json"))
	_check_format_loader()
	_check_bone_matrix("mat4-float", 2e-4, true)
	_check_bone_matrix("qpos-u16", 0.02, false)
	_check_held_rows()
	load(ROOT + "/check_conformance.gd").new(self).run()
	await load(ROOT + "/check_conformance_gpu.gd").new(self).run()
	var mesh := _cow_mesh()
	if mesh == null:
		return
	_make_viewport()
	var roster = ResourceLoader.load(COW + "/roster/roster.json", "CrowdbakeRoster")
	_check_instance_numbers(roster, mesh)
	_check_timed_roster(mesh)
	_check_travel(roster, mesh)
	_check_bounds(roster, mesh)
	_check_manifest_footsteps(mesh, "roster") # before _check_footsteps changes the roster
	_check_manifest_footsteps(mesh, "timed") # timed rows: the contacts on cells
	_check_footsteps(roster, mesh)
	_check_sockets(roster, mesh)
	var look = load(ROOT + "/check_addon_look.gd").new(self)
	look.check_socket_scale(roster, mesh)
	await _check_drawing(roster, mesh)
	await look.check_look("cow", COW + "/Cow.glb", COW + "/roster/roster.json", 7)
	await look.check_look("husky", look.HUSKY + "/Husky.glb", look.HUSKY + "/roster/roster.json", 5)
	await look.check_lod(roster, mesh)
	await look.check_far_tier(roster, mesh)
	await look.check_demo()
	look.check_imported_palette()
	look.check_imported_roster(mesh)
	await _check_shadow(roster, mesh)
	_viewport.queue_free()

# "expect-error:" stays first: the runner reads it there.
static func _label(name: String) -> String:
	return "expect-error: addon: " + name.trim_prefix("expect-error: ") if name.begins_with("expect-error: ") else "addon: " + name

func _begin(name: String) -> void:
	check._begin(_label(name))

func _end(name: String, why := "") -> void:
	check._end(_label(name), why)

# Cow.fps30.csv's Walk and Death rows (test_godot.c greps them out of the 7.8 MB file).
func _read_reference(path: String) -> void:
	for line in FileAccess.get_file_as_string(path).split("\n", false):
		var f := line.split(",")
		var clip := f[1].trim_prefix("\"").trim_suffix("\"")
		var frame := int(f[2])
		if not _reference.has(clip):
			_reference[clip] = {}
		if not _reference[clip].has(frame):
			_reference[clip][frame] = [float(f[4]), []]
		var m := PackedFloat64Array()
		for k in 16:
			m.append(float(f[7 + k]))
		_reference[clip][frame][1].append(m)

# load() reads a .pal and, with the type hint, a roster; the clip table agrees with the manifest.
func _check_format_loader() -> void:
	var name := "load() gives a CrowdbakePalette and a CrowdbakeRoster"
	_begin(name)
	ResourceLoader.add_resource_format_loader(load(ADDON + "/crowdbake_format_loader.gd").new())
	var pal = ResourceLoader.load(COW + "/roster/cow.pal", "", ResourceLoader.CACHE_MODE_IGNORE)
	var roster = ResourceLoader.load(COW + "/roster/roster.json", "CrowdbakeRoster", ResourceLoader.CACHE_MODE_IGNORE)
	var plain = ResourceLoader.load(COW + "/roster/roster.json", "", ResourceLoader.CACHE_MODE_IGNORE)
	var why := ""
	var want: Array = _manifest["types"]["cow"]["clips"]
	if pal == null or pal.get("clips") == null or roster == null or roster.get("types") == null:
		why = "load() returned %s and %s" % [pal, roster]
	elif not plain is JSON:
		why = "a .json without the type hint is no longer Godot's JSON resource: %s" % plain
	elif pal.clips.size() != want.size() or roster.types["cow"]["palette"].clips.size() != want.size():
		why = "%d clips, the manifest lists %d" % [pal.clips.size(), want.size()]
	elif pal.texture.get_width() != _manifest["types"]["cow"]["width"]:
		why = "texture %d texels wide, manifest %d" % [pal.texture.get_width(), _manifest["types"]["cow"]["width"]]
	else:
		for i in want.size():
			var c: Dictionary = pal.clips[i]
			if c["name"] != want[i]["name"] or c["first_row"] != want[i]["first_row"] or c["frames"] != want[i]["frame_count"] \
					or absf(c["fps"] - want[i]["fps"]) > 1e-4 or c["loops"] != want[i]["loops"]:
				why = "clip %d is %s, the manifest says %s" % [i, c, want[i]]
	_end(name, why)
	name = "expect-error: load() refuses a truncated palette"
	_begin(name)
	var bytes := FileAccess.get_file_as_bytes(COW + "/roster/cow.pal")
	var f := FileAccess.open(ROOT + "/truncated.pal", FileAccess.WRITE)
	f.store_buffer(bytes.slice(0, 1000))
	f.close()
	var damaged = ResourceLoader.load(ROOT + "/truncated.pal", "", ResourceLoader.CACHE_MODE_IGNORE)
	_end(name, "" if damaged == null else "loaded")

# The largest difference between a matrix and a reference row (16 floats, column-major).
static func _difference(m: Transform3D, ref: PackedFloat64Array) -> float:
	var got := [m.basis.x.x, m.basis.x.y, m.basis.x.z, 0.0, m.basis.y.x, m.basis.y.y, m.basis.y.z, 0.0,
			m.basis.z.x, m.basis.z.y, m.basis.z.z, 0.0, m.origin.x, m.origin.y, m.origin.z, 1.0]
	var worst := 0.0
	for k in 16:
		worst = maxf(worst, absf(got[k] - ref[k]))
	return worst

static func _mix(a: PackedFloat64Array, b: PackedFloat64Array, w: float) -> PackedFloat64Array:
	var out := PackedFloat64Array()
	for k in 16:
		out.append(a[k] + (b[k] - a[k]) * w)
	return out

# bone_matrix against the reference CSV, every bone: at each row time (a loop also one duration later,
# wrapped), a one-shot clamped past its end, and (linear layouts) halfway between rows, where the
# shaders blend the two rows linearly. The same comparison one row off must fail it.
func _check_bone_matrix(bake: String, tolerance: float, halfway: bool) -> void:
	var name := "bone_matrix equals Cow.fps30.csv: " + bake
	_begin(name)
	var pal = load(ADDON + "/crowdbake_palette.gd").new()
	if not pal.load_file(COW + "/" + bake + ".pal"):
		return _end(name, pal.error)
	var worst := 0.0
	var one_row_off := 0.0
	for clip in [WALK, DEATH]:
		var rows: Dictionary = _reference[clip]
		var c: Dictionary = pal.clips[pal.clip_index(clip)]
		var last: int = c["frames"] - 1 # a loop's frame N (its frame 0) is checked one duration later
		var t0: float = rows[0][0]
		for i in last + 1:
			var t: float = rows[i][0] - t0
			for bone in pal.bone_names.size():
				worst = maxf(worst, _difference(pal.bone_matrix(clip, t, bone), rows[i][1][bone]))
				if c["loops"]:
					worst = maxf(worst, _difference(pal.bone_matrix(clip, t + c["duration"], bone), rows[i][1][bone]))
				if halfway and i < last:
					var mid: float = (rows[i][0] + rows[i + 1][0]) / 2.0 - t0
					worst = maxf(worst, _difference(pal.bone_matrix(clip, mid, bone), _mix(rows[i][1][bone], rows[i + 1][1][bone], 0.5)))
				if i < last:
					one_row_off = maxf(one_row_off, _difference(pal.bone_matrix(clip, t, bone), rows[i + 1][1][bone]))
		if not c["loops"]:
			for bone in pal.bone_names.size():
				worst = maxf(worst, _difference(pal.bone_matrix(clip, 100.0, bone), rows[last][1][bone]))
	print("crowdbake-check: %s worst %s (tolerance %s); compared with the next row it would be %s" % [bake, worst, tolerance, one_row_off])
	_end(name, "" if worst <= tolerance and one_row_off > 10.0 * tolerance else "worst %s, one row off %s" % [worst, one_row_off])
	name = "expect-error: bone_matrix refuses a clip or bone that does not exist: " + bake
	_begin(name)
	var refused: bool = pal.bone_matrix("no such clip", 0.0, 0) == null and pal.bone_matrix(WALK, 0.0, pal.bone_names.size()) == null
	_end(name, "" if refused and pal.error.contains("no clip") else "returned a matrix")

# The shared STEP SimpleSkin (.pal version 4): its clip's rows are held, not blended. Between two rows
# bone_matrix is the earlier row's alone (frame_at: that row twice, weight 0), where a blend of the two
# would differ: the rows are the keys' poses.
func _check_held_rows() -> void:
	var name := "a STEP-keyed clip's rows are held (version 4)"
	_begin(name)
	var pal = load(ADDON + "/crowdbake_palette.gd").new()
	if not pal.load_file(ROOT + "/bakes/step/step.pal"):
		return _end(name, pal.error)
	var c: Dictionary = pal.clips[0]
	var worst := 0.0
	var blended := 0.0
	for r in c["frames"] - 1:
		var frame: Array = pal.frame_at(pal.clip_instance(0), (r + 0.75) / c["fps"])
		if frame != [c["first_row"] + r, c["first_row"] + r, 0.0]:
			return _end(name, "frame_at gave %s at row %d" % [frame, r])
		for bone in pal.bone_names.size():
			var at: Transform3D = pal.bone_matrix(0, (r + 0.05) / c["fps"], bone)
			var later: Transform3D = pal.bone_matrix(0, (r + 0.75) / c["fps"], bone)
			var next: Transform3D = pal.bone_matrix(0, (r + 1.05) / c["fps"], bone)
			worst = maxf(worst, (later.origin - at.origin).length() + (later.basis.x - at.basis.x).length())
			blended = maxf(blended, (next.basis.x - at.basis.x).length())
	_end(name, "" if c["step"] and worst < 1e-6 and blended > 0.01 else "step %s, held rows differ by %s, rows %s apart" % [c["step"], worst, blended])

# Cow's skinned mesh as Godot's own glTF importer reads it.
func _cow_mesh() -> Mesh:
	var name := "Cow.glb's skinned mesh through GLTFDocument"
	_begin(name)
	var doc := GLTFDocument.new()
	var state := GLTFState.new()
	var err := doc.append_from_file(COW + "/Cow.glb", state)
	var scene := doc.generate_scene(state) if err == OK else null
	var mesh: Mesh = _herd_script.skinned_mesh_in(scene) if scene else null
	if scene:
		scene.free()
	_end(name, "" if mesh != null else "no skinned mesh (error %d)" % err)
	return mesh

func _make_viewport() -> void:
	_viewport = SubViewport.new()
	_viewport.size = Vector2i(64, 64)
	_viewport.render_target_update_mode = SubViewport.UPDATE_ALWAYS
	_viewport.transparent_bg = true
	_viewport.own_world_3d = true
	check.add_child(_viewport)
	_camera = Camera3D.new()
	_viewport.add_child(_camera)
	var light := DirectionalLight3D.new()
	light.transform = Transform3D(Basis.looking_at(Vector3(1, -0.5, 0).normalized(), Vector3.UP), Vector3.ZERO)
	light.shadow_enabled = true
	light.directional_shadow_max_distance = 20.0
	_viewport.add_child(light)

func _new_herd(roster, mesh: Mesh, count: int) -> MultiMeshInstance3D:
	var herd: MultiMeshInstance3D = _herd_script.new()
	herd.playing = false # the test moves the clock
	_viewport.add_child(herd)
	if not herd.setup(roster, "cow", mesh, count):
		push_error(herd.error)
	for i in count:
		herd.place(i, Transform3D(Basis.from_scale(Vector3.ONE * SIZE), Vector3.ZERO))
	return herd

# set_state and set_speed write the manifest's numbers, scaled so the feet stay planted, keep the
# pose when the speed changes, and cross-fade the matrices as the shader mixes the skinned points.
func _check_instance_numbers(roster, mesh: Mesh) -> void:
	var name := "set_state and set_speed: the manifest's numbers, rate = speed / (scale x speed_reference)"
	_begin(name)
	var herd := _new_herd(roster, mesh, 3)
	var states: Dictionary = _manifest["types"]["cow"]["states"]
	var fps: float = states["run"]["instance"]["rate"]
	herd.place(1, Transform3D(Basis.from_scale(Vector3.ONE * 2.0), Vector3(3, 0, 0)))
	herd.advance(0.7)
	herd.set_state(1, "run", 0.0)
	var before: Transform3D = herd.bone_transform_at(1, 10)
	herd.set_speed(1, 5.0)
	var after: Transform3D = herd.bone_transform_at(1, 10)
	var run: Vector4 = herd.instance_numbers(1)
	var ground_speed: float = _manifest["types"]["cow"]["clips"].filter(func(c): return c["name"] == states["run"]["clip"])[0]["ground_speed"]
	var want_rate := fps * 5.0 / (2.0 * ground_speed) # rows per second: the clip's fps x speed / (scale x its ground speed)
	herd.set_state(2, "graze", 0.0)
	herd.set_speed(2, 5.0)
	var graze: Vector4 = herd.instance_numbers(2)
	var why := ""
	if run.x != states["run"]["instance"]["first_row"] or run.y != states["run"]["instance"]["frame_count"]:
		why = "run plays rows %s, the manifest says %s" % [run, states["run"]["instance"]]
	elif absf(run.z - want_rate) > 1e-4 * want_rate:
		why = "run at 5 m/s and scale 2 plays %s rows/s, want %s" % [run.z, want_rate]
	elif graze.z != float(states["graze"]["instance"]["rate"]):
		why = "graze (a time state) plays %s rows/s at 5 m/s, its own rate is %s" % [graze.z, states["graze"]["instance"]["rate"]]
	elif (before.origin - after.origin).length() > 1e-3 or not before.basis.is_equal_approx(after.basis):
		why = "the pose jumped when the speed changed: %s -> %s" % [before, after]
	else:
		var from: Vector4 = herd.instance_numbers(0)
		herd.set_state(0, "run", 0.5)
		herd.advance(0.25)
		var pal = herd.palette
		var a: Transform3D = pal.matrix_at(from, herd.time, 10)
		var b: Transform3D = pal.matrix_at(herd.instance_numbers(0), herd.time, 10)
		var mixed: Transform3D = herd.multimesh.get_instance_transform(0) * Transform3D(Basis((a.basis.x + b.basis.x) / 2.0, (a.basis.y + b.basis.y) / 2.0, (a.basis.z + b.basis.z) / 2.0), (a.origin + b.origin) / 2.0)
		var got: Transform3D = herd.bone_transform_at(0, 10)
		if herd.instance_numbers(0, true) != from or not got.is_equal_approx(mixed):
			why = "halfway through a cross-fade: %s, want %s" % [got, mixed]
	herd.queue_free()
	_end(name, why)

# The Cow roster baked with local, timed rows (test_godot.c: bakes/cow/timed; docs/roster.md): every clip timed, its
# states' frame_count its cells and their rates negative. The roster reads; set_state and set_speed write the cells and
# keep z < 0: -1e-30 standing still, -|rate_per_speed| x speed / scale moving (speed sync kept), a time state its rate.
# A timed state whose frame_count is not its clip's cells is refused, one line.
func _check_timed_roster(mesh: Mesh) -> void:
	var name := "timed roster: cells, z < 0 (-1e-30 standing still), -|rate_per_speed| x speed / scale moving"
	_begin(name)
	var path := COW + "/timed/roster.json"
	var manifest: Dictionary = JSON.parse_string(FileAccess.get_file_as_string(path))
	var roster = ResourceLoader.load(path, "CrowdbakeRoster", ResourceLoader.CACHE_MODE_IGNORE)
	var why := "" if roster != null and roster.get("types") != null else "the timed roster did not load"
	var cow: Dictionary = manifest["types"]["cow"]
	var timed := 0
	var synced := 0
	var herd: MultiMeshInstance3D = _new_herd(roster, mesh, 3) if why.is_empty() else null
	for state in cow["states"] if herd else []:
		var inst: Dictionary = cow["states"][state]["instance"]
		var clip: Dictionary = cow["clips"].filter(func(c): return c["name"] == cow["states"][state]["clip"])[0]
		var cells := int(clip.get("timed_rows", {}).get("cells", 0))
		var per_speed: float = inst["rate_per_speed"]
		herd.set_state(1, state, 0.0)
		herd.set_speed(1, 0.0)
		var still: Vector4 = herd.instance_numbers(1)
		herd.set_speed(1, 2.0)
		var moving: Vector4 = herd.instance_numbers(1)
		var want_still: float = inst["rate"] if per_speed == 0.0 else -1e-30
		var want: float = inst["rate"] if per_speed == 0.0 else -absf(per_speed) * 2.0 / SIZE
		timed += 1 if cells > 0 else 0
		synced += 1 if per_speed != 0.0 else 0
		if cells == 0 or absi(int(inst["frame_count"])) != cells or still.y != inst["frame_count"] or moving.x != inst["first_row"]:
			why = "%s plays %s; the manifest says %s, its clip %d cells" % [state, moving, inst, cells]
		elif not (still.z < 0.0 and moving.z < 0.0) or absf(still.z - want_still) > 1e-6 * absf(want_still) \
				or absf(moving.z - want) > 1e-4 * absf(want):
			why = "%s: z %s standing still, %s at 2 m/s; want %s and %s (z < 0 marks a timed instance)" % [state, still.z, moving.z, want_still, want]
		if not why.is_empty():
			break
	if herd:
		herd.queue_free()
	if why.is_empty() and (timed == 0 or synced == 0):
		why = "%d timed states, %d that follow the speed: want some of each" % [timed, synced]
	_end(name, why)
	name = "expect-error: a timed state whose frame_count is not its clip's cells is refused"
	_begin(name)
	var damaged: Dictionary = manifest.duplicate(true)
	damaged["types"]["cow"]["states"]["wander"]["instance"]["frame_count"] += 1
	var f := FileAccess.open(COW + "/timed/damaged.json", FileAccess.WRITE)
	f.store_string(JSON.stringify(damaged))
	f.close()
	var refused = load(ADDON + "/crowdbake_roster.gd").new()
	why = "read" if refused.load_file(COW + "/timed/damaged.json") else ""
	if why.is_empty() and (not refused.error.contains("types.cow.states.wander.instance.frame_count: clip") \
			or not refused.error.contains(" cells, got ") or refused.error.contains("\n")):
		why = "its error: " + refused.error
	_end(name, why)

# A placed instance galloping at speed is drawn at its place plus the .pal's per-row travel offset
# (version 5), read here from the file's bytes (the table at header byte 192, the clip's heading at
# its entry's byte 68), blended between rows as frame_at picks them; a walk (no offsets) and a
# gallop at standstill stay at their places.
func _check_travel(roster, mesh: Mesh) -> void:
	var name := "a placed gallop is drawn at its place plus the .pal's travel offset; a walk at its place"
	_begin(name)
	var herd := _new_herd(roster, mesh, 3)
	var bytes := FileAccess.get_file_as_bytes(COW + "/roster/" + _manifest["types"]["cow"]["palette"])
	var table := bytes.decode_u64(192) if bytes.decode_u32(12) & 16 else 0
	var place := Transform3D(Basis(Vector3.UP, 0.7).scaled(Vector3.ONE * 2.0), Vector3(3, 0, -1))
	for i in 3:
		herd.set_state(i, ["run", "wander", "run"][i], 0.0)
		herd.set_speed(i, [5.0, 2.0, 0.0][i])
		herd.place(i, place)
	var why := "" if table != 0 else "the palette has no travel table (version %d)" % bytes.decode_u32(8)
	var moved := 0.0
	for step in 5:
		herd.advance(0.13)
		var inst: Vector4 = herd.instance_numbers(0)
		var frame: Array = herd.palette.frame_at(inst, herd.time)
		var entry := -1
		for c in bytes.decode_u32(60):
			if bytes.decode_u32(bytes.decode_u64(120) + c * 80 + 8) == int(inst.x):
				entry = bytes.decode_u64(120) + c * 80
		if why.is_empty() and entry >= 0:
			var heading := Vector3(bytes.decode_float(entry + 68), bytes.decode_float(entry + 72), bytes.decode_float(entry + 76))
			var o := lerpf(bytes.decode_float(table + 4 * frame[0]), bytes.decode_float(table + 4 * frame[1]), frame[2])
			var want := place * (heading * o)
			var got := herd.multimesh.get_instance_transform(0).origin
			moved = maxf(moved, (got - place.origin).length())
			if heading == Vector3.ZERO or (got - want).length() > 1e-4:
				why = "at %s s the gallop is at %s, want %s (heading %s)" % [herd.time, got, want, heading]
			for i in [1, 2]:
				if why.is_empty() and (herd.multimesh.get_instance_transform(i).origin - place.origin).length() > 1e-6:
					why = "instance %d (%s) moved off its place" % [i, ["", "a walk", "a gallop at standstill"][i]]
	if why.is_empty() and moved < 1e-3:
		why = "the gallop's offsets moved it only %s" % moved
	herd.queue_free()
	_end(name, why)

# The MultiMesh's custom AABB holds every vertex of Cow's mesh skinned at many times, states and
# places; the clip bounds alone, without the instances' places, would not.
func _check_bounds(roster, mesh: Mesh) -> void:
	var name := "custom AABB holds every animated vertex"
	_begin(name)
	var herd := _new_herd(roster, mesh, 3)
	herd.place(1, Transform3D(Basis(Vector3.UP, 0.8).scaled(Vector3.ONE * 0.3), Vector3(-12, 0, 2)))
	herd.place(2, Transform3D(Basis(Vector3.UP, 2.0).scaled(Vector3.ONE * 1.2), Vector3(15, 1, -3)))
	herd.set_state(1, "graze", 0.0)
	herd.set_state(2, "run", 0.0)
	herd.update_bounds()
	var box: AABB = herd.multimesh.custom_aabb.grow(1e-4)
	var clip_box: AABB = herd.palette.largest_bounds().grow(1e-4) # without the instances' places
	var arrays := mesh.surface_get_arrays(0)
	var vertices: PackedVector3Array = arrays[Mesh.ARRAY_VERTEX]
	var bones: PackedInt32Array = arrays[Mesh.ARRAY_BONES]
	var weights: PackedFloat32Array = arrays[Mesh.ARRAY_WEIGHTS]
	var per := bones.size() / vertices.size()
	var outside := 0
	var outside_bind := 0
	var checked := 0
	for step in 6:
		herd.advance(0.37)
		for i in 3:
			var mats := []
			for bone in herd.palette.bone_names.size():
				mats.append(herd.bone_transform_at(i, bone))
			for v in vertices.size():
				var p := Vector3.ZERO
				for k in per:
					p += weights[v * per + k] * (mats[bones[v * per + k]] * vertices[v])
				outside += 0 if box.has_point(p) else 1
				outside_bind += 0 if clip_box.has_point(p) else 1
				checked += 1
	print("crowdbake-check: %d skinned vertices, %d outside the herd's AABB %s, %d outside the clip bounds without the instances' places"
			% [checked, outside, box, outside_bind])
	var why := ""
	if herd.get_aabb() != herd.multimesh.custom_aabb:
		why = "the node's AABB %s is not the custom one %s" % [herd.get_aabb(), herd.multimesh.custom_aabb]
	elif outside > 0 or outside_bind == 0:
		why = "%d vertices outside the herd's AABB; %d outside the clip bounds alone" % [outside, outside_bind]
	herd.queue_free()
	_end(name, why)

# Footsteps: a contact list in the manifest's shape (contacts: [{foot, bone, time, lift}] per clip)
# raises footstep and foot_lifted once per cycle, on the frame the clip time crosses it; a state
# whose clip has none raises nothing.
func _check_footsteps(roster, mesh: Mesh) -> void:
	var name := "footstep signals at the manifest's contacts"
	_begin(name)
	roster.types["cow"]["clips"][WALK]["contacts"] = [{"foot": "FL", "bone": 37, "time": 0.11, "lift": 0.5}]
	var herd := _new_herd(roster, mesh, 2)
	var speed_reference: float = _manifest["types"]["cow"]["speed_reference"]
	herd.set_state(0, "wander", 0.0)
	herd.set_speed(0, speed_reference * SIZE) # playback rate 1: the clip's own time
	herd.set_state(1, "graze", 0.0)
	var steps := []
	var lifts := []
	herd.footstep.connect(func(i, foot, bone): steps.append([i, foot, bone, herd.time]))
	herd.foot_lifted.connect(func(i, _foot, _bone): lifts.append([i, herd.time]))
	var phase: float = herd.instance_numbers(0).w # instance 0's golden-ratio phase is 0: the clip starts at time 0
	for n in 140: # two Walk cycles (35 rows at 30 fps) in 60 Hz frames
		herd.advance(1.0 / 60.0)
	var lands := [0.11, 0.11 + 35.0 / 30.0] # each on the first frame at or past it
	var why := ""
	if steps.size() != 2 or lifts.size() != 2:
		why = "%d footsteps and %d lifts in two cycles: %s %s" % [steps.size(), lifts.size(), steps, lifts]
	elif steps[0][0] != 0 or steps[0][1] != "FL" or steps[0][2] != 37:
		why = "footstep %s, want instance 0, foot FL, bone 37" % [steps[0]]
	elif phase != 0.0:
		why = "instance 0 starts at phase %s" % phase
	else:
		for k in 2:
			if steps[k][3] < lands[k] or steps[k][3] > lands[k] + 1.0 / 60.0 + 1e-6:
				why = "footstep %d came at %.4f s, the contact is at %.4f s" % [k, steps[k][3], lands[k]]
	print("crowdbake-check: footsteps at %s, lifts at %s" % [steps, lifts])
	herd.queue_free()
	_end(name, why)

# The contacts crowdbake wrote for Cow's Gallop (the run state) in the roster of COW/`bake` ("roster", or "timed":
# local, timed rows, whose instance counts cells): played at its own rate (speed = its ground speed), two cycles raise
# each listed landing twice, each on the first 60 Hz frame at or past its time; and the 14 sockets it lists are read
# by name.
func _check_manifest_footsteps(mesh: Mesh, bake: String) -> void:
	var path := COW + "/" + bake + "/roster.json"
	var manifest: Dictionary = JSON.parse_string(FileAccess.get_file_as_string(path))
	var cow: Dictionary = manifest["types"]["cow"]
	var clip: Dictionary = cow["clips"].filter(func(c): return c["name"] == cow["states"]["run"]["clip"])[0]
	var name := "footsteps at Cow's own contacts (the run state%s), sockets by name" % (", timed rows" if clip.has("timed_rows") else "")
	_begin(name)
	var roster = ResourceLoader.load(path, "CrowdbakeRoster", ResourceLoader.CACHE_MODE_IGNORE)
	var contacts: Array = clip.get("contacts", [])
	var herd := _new_herd(roster, mesh, 1)
	herd.set_state(0, "run", 0.0)
	herd.set_speed(0, clip["ground_speed"] * SIZE) # playback rate 1: clip time = herd time
	var steps := []
	herd.footstep.connect(func(_i, foot, bone): steps.append([foot, bone, herd.time]))
	var frames := int(ceilf(2.0 * clip["duration"] * 60.0))
	for n in frames:
		herd.advance(1.0 / 60.0)
	var want := []
	for cycle in 2:
		for c in contacts:
			if c["time"] + cycle * clip["duration"] <= herd.time:
				want.append([c["foot"], int(c["bone"]), c["time"] + cycle * clip["duration"]])
	want.sort_custom(func(a, b): return a[2] < b[2])
	var why := ""
	if bake == "timed" and not clip.has("timed_rows"):
		why = "the timed bake's run clip has no timed rows"
	elif contacts.size() < 2 or steps.size() != want.size():
		why = "%d footsteps, the manifest's %d contacts make %d: %s" % [steps.size(), contacts.size(), want.size(), steps]
	else:
		for k in want.size():
			if steps[k][0] != want[k][0] or steps[k][1] != want[k][1] or steps[k][2] < want[k][2] - 1e-4 or steps[k][2] > want[k][2] + 1.0 / 60.0 + 1e-4:
				why = "footstep %d: %s, want %s (time up to a frame later)" % [k, steps[k], want[k]]
				break
	var sockets: Array = cow.get("sockets", [])
	if why.is_empty() and (sockets.size() != roster.types["cow"]["sockets"].size() or sockets.is_empty()
			or herd.socket_transform(0, sockets[0]["name"]) == null):
		why = "the manifest lists %d sockets, the roster read %d" % [sockets.size(), roster.types["cow"]["sockets"].size()]
	print("crowdbake-check: %d footsteps in two run cycles from %d contacts; %d sockets" % [steps.size(), contacts.size(), sockets.size()])
	herd.queue_free()
	_end(name, why)

# Sockets of the manifest's shape ([{name, bone, bind_transform}]) follow their bone.
func _check_sockets(roster, mesh: Mesh) -> void:
	var name := "socket_transform follows its bone"
	_begin(name)
	roster.types["cow"]["sockets"] = load(ADDON + "/crowdbake_roster.gd")._sockets(
			[{"name": "bell", "bone": 5, "bind_transform": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0.5, 0.25, 1]}])
	var herd := _new_herd(roster, mesh, 1)
	herd.advance(0.4)
	var got: Transform3D = herd.socket_transform(0, "bell")
	var want: Transform3D = herd.bone_transform_at(0, 5) * Transform3D(Basis(), Vector3(0, 0.5, 0.25))
	herd.queue_free()
	_end(name, "" if got.is_equal_approx(want) else "%s, want %s" % [got, want])

func _frame() -> Image:
	await RenderingServer.frame_post_draw
	await RenderingServer.frame_post_draw
	return _viewport.get_texture().get_image()

# Mean colour and count of the covered pixels (the background is transparent).
static func _covered(image: Image) -> Array:
	var sum := Color(0, 0, 0, 0)
	var n := 0
	for y in image.get_height():
		for x in image.get_width():
			var c := image.get_pixel(x, y)
			if c.a > 0.0:
				sum += c
				n += 1
	return [sum / maxf(n, 1), n]

static func _differ(a: Image, b: Image) -> int:
	var n := 0
	for y in a.get_height():
		for x in a.get_width():
			n += 1 if (a.get_pixel(x, y) - b.get_pixel(x, y)).get_luminance() > 0.02 or (b.get_pixel(x, y) - a.get_pixel(x, y)).get_luminance() > 0.02 else 0
	return n

# Drawn by Godot: the herd shows in view and is culled behind the camera, an instance colour tints it,
# and set_state changes the pose drawn (setting the state it is in does not).
func _check_drawing(roster, mesh: Mesh) -> void:
	var white_mesh: Mesh = mesh.duplicate() # without its materials: a white herd, whose tint shows plainly
	for s in white_mesh.get_surface_count():
		white_mesh.surface_set_material(s, null)
	var herd := _new_herd(roster, white_mesh, 1)
	_camera.transform = Transform3D(Basis(), Vector3(0, 0.35, 1.4))
	herd.place(0, Transform3D(Basis(Vector3.UP, PI / 2).scaled(Vector3.ONE * SIZE), Vector3.ZERO)) # side on
	var name := "the herd draws in view, and nothing behind the camera"
	_begin(name)
	var white := _covered(await _frame())
	var drawn := _viewport.get_render_info(Viewport.RENDER_INFO_TYPE_VISIBLE, Viewport.RENDER_INFO_OBJECTS_IN_FRAME)
	herd.place(0, Transform3D(Basis.from_scale(Vector3.ONE * SIZE), Vector3(0, 0, 6)))
	var behind := _covered(await _frame())
	var culled := _viewport.get_render_info(Viewport.RENDER_INFO_TYPE_VISIBLE, Viewport.RENDER_INFO_OBJECTS_IN_FRAME)
	herd.place(0, Transform3D(Basis(Vector3.UP, PI / 2).scaled(Vector3.ONE * SIZE), Vector3.ZERO))
	print("crowdbake-check: %d pixels, %d objects in view; %d pixels, %d objects behind the camera" % [white[1], drawn, behind[1], culled])
	_end(name, "" if white[1] > 50 and drawn >= 1 and behind[1] == 0 and culled == 0 else "see the numbers above")
	name = "an instance colour tints the herd"
	_begin(name)
	herd.set_color(0, Color(1, 0.1, 0.1))
	var red := _covered(await _frame())
	print("crowdbake-check: mean colour white %s, tinted %s" % [white[0], red[0]])
	var tinted: bool = red[0].g < 0.3 * white[0].g and red[0].r > 0.6 * white[0].r
	_end(name, "" if tinted and white[0].g > 0.05 else "white %s, tinted %s" % [white[0], red[0]])
	name = "set_state changes the pose drawn"
	_begin(name)
	herd.set_state(0, "wander", 0.0) # from a walk: the roster's default state is decided by name now (graze)
	var walk := await _frame()
	herd.set_state(0, "wander", 0.0)
	var same := _differ(walk, await _frame())
	herd.set_state(0, "graze", 0.0)
	var graze := _differ(walk, await _frame())
	print("crowdbake-check: %d pixels change setting the state it is in, %d going to graze" % [same, graze])
	_end(name, "" if same == 0 and graze > 20 else "%d and %d pixels changed" % [same, graze])
	herd.queue_free()
	await _check_other_layout(roster, mesh)

# The herd rewrites its shader's defines to the palette's layout and precision: Cow's mat4/float bake
# (the same clips and rows) draws the pose the default qpos/u16 one draws.
func _check_other_layout(roster, mesh: Mesh) -> void:
	var name := "a mat4/float palette draws the herd as qpos/u16 does"
	_begin(name)
	var masks := []
	var default_palette = roster.types["cow"]["palette"]
	var mat4 = load(ADDON + "/crowdbake_palette.gd").new()
	mat4.load_file(COW + "/mat4-states.pal")
	for palette in [default_palette, mat4]:
		roster.types["cow"]["palette"] = palette
		var herd := _new_herd(roster, mesh, 1)
		herd.place(0, Transform3D(Basis(Vector3.UP, PI / 2).scaled(Vector3.ONE * SIZE), Vector3.ZERO))
		herd.set_state(0, "graze", 0.0)
		herd.advance(2.5)
		var image := await _frame()
		var mask := PackedByteArray()
		for y in image.get_height():
			for x in image.get_width():
				mask.append(1 if image.get_pixel(x, y).a > 0.0 else 0)
		masks.append(mask)
		herd.queue_free()
	roster.types["cow"]["palette"] = default_palette
	var differ := 0
	for i in masks[0].size():
		differ += 1 if masks[0][i] != masks[1][i] else 0
	print("crowdbake-check: %d of %d covered pixels differ" % [differ, masks[0].count(1)])
	_end(name, "" if masks[0].count(1) > 50 and differ * 50 <= masks[0].count(1) else "%d of %d covered pixels differ" % [differ, masks[0].count(1)])

# The shadow pass skins too: looking down at the ground under a herd that casts only shadows, the
# shadow differs between two times; a herd standing still (speed 0) casts the same shadow.
func _check_shadow(roster, mesh: Mesh) -> void:
	var name := "the shadow moves with the animation"
	_begin(name)
	var ground := MeshInstance3D.new()
	ground.mesh = PlaneMesh.new()
	ground.mesh.size = Vector2(20, 20)
	_viewport.add_child(ground)
	# A perspective camera: Godot 4.6's Compatibility renderer drew no directional shadow for an
	# orthographic one here.
	_camera.transform = Transform3D(Basis.looking_at(Vector3(0, -1, -0.01), Vector3.FORWARD), Vector3(0.8, 2.0, 0))
	var herd := _new_herd(roster, mesh, 1)
	herd.cast_shadow = GeometryInstance3D.SHADOW_CASTING_SETTING_SHADOWS_ONLY # only its shadow in view
	herd.set_state(0, "wander", 0.0)
	herd.set_speed(0, _manifest["types"]["cow"]["speed_reference"] * SIZE)
	var a := await _frame()
	herd.advance(0.45)
	var b := await _frame()
	var lit := a.get_pixel(63, 32).get_luminance() # the lit ground, far from the shadow
	var dark := 0
	for y in a.get_height():
		for x in a.get_width():
			dark += 1 if a.get_pixel(x, y).get_luminance() < 0.6 * lit else 0
	herd.set_speed(0, 0.0)
	var c := await _frame()
	herd.advance(0.45)
	var still := _differ(c, await _frame())
	var moved := _differ(a, b)
	print("crowdbake-check: %d shadow pixels; %d change in 0.45 s walking, %d standing still" % [dark, moved, still])
	herd.queue_free()
	ground.queue_free()
	_end(name, "" if dark > 20 and moved > 10 and still == 0 else "see the numbers above")
