# crowdbake_herd.gd - a herd of one animal type as one MultiMeshInstance3D: one draw call, no
# Skeleton3D, no AnimationPlayer. Each instance plays a state of the roster manifest at its own
# speed, cross-fades between states, takes a colour and a uniform scale, and reports its footsteps.
#
#   var herd := CrowdbakeHerd.new()
#   herd.setup(load("res://roster/roster.json"), "cow", preload("res://cow_mesh.tres"), 100)  # the plugin's import
#   (without the plugin: ResourceLoader.load("res://roster/roster.json", "CrowdbakeRoster"))
#   add_child(herd)
#   herd.place(7, Transform3D(Basis().scaled(Vector3.ONE * 1.2), Vector3(3, 0, 1)))
#   herd.set_state(7, "run")      # cross-fades over fade_seconds
#   herd.set_speed(7, 4.0)        # metres per second: the feet stay planted at any scale
#   herd.footstep.connect(func(i, foot, bone): ...)
#
# The mesh is the animal's skinned mesh (bone indices = the palette's bones, as in the glTF skin). The
# herd keeps its look: each surface's material (base colour, texture, vertex colours, alpha scissor)
# on its own copy of the herd's shader, plain-colour surfaces merged into one (one draw call):
# crowdbake_herd_mesh.gd.
# A placed instance moving at a state's speed is drawn at its place plus the palette's per-row travel
# offset (.pal version 5: travel_offset), so a gallop's planted feet stay still.
# The instances' clip numbers live in a float texture (crowdbake_herd.gdshader), and the herd keeps
# its own clock (`time`), so the CPU side (bone_transform_at, sockets, footsteps) sees the pose the
# GPU draws.
class_name CrowdbakeHerd
extends MultiMeshInstance3D

signal footstep(instance: int, foot: String, bone: int) # a foot lands (the manifest's contacts)
signal foot_lifted(instance: int, foot: String, bone: int)

const _SHADER := preload("crowdbake_herd.gdshader")
const _INCLUDE := preload("crowdbake_palette.gdshaderinc")
const _HERD_MESH := preload("crowdbake_herd_mesh.gd")
const _BONE_PASS_SHADER := preload("crowdbake_bone_pass.gdshader")
const _BONE_PASS_INCLUDE := preload("crowdbake_bone_pass.gdshaderinc")
const GOLDEN := 0.6180339887
# The rate a timed instance (rate < 0, .pal version 7) plays at standstill (crowdbake_pal.mjs TIMED_STILL_RATE): it
# stays negative to mark the instance timed (-0 reads as an untimed clip's, its cells taken for rows).
const TIMED_STILL_RATE := 1e-30
const INSTANCES_PER_ROW := 256 # instances per row of the instance texture
const FLOATS := 12 # per instance: current clip (4), previous clip (4), fade start and length, far tier (1), 1 spare

@export var roster: Resource # a CrowdbakeRoster
@export var animal := ""
@export var mesh: Mesh
@export var count := 0
@export var fade_seconds := 0.25 # set_state's cross-fade
@export var playing := true # advance the clock in _process
# Animation LOD: an instance under lod.x pixels tall on screen is skinned with its 2 largest bone
# weights, under lod.y with its largest alone (the kept weights scaled to sum to 1): the rule crowdbake
# mesh --max-influences 2|1 applies to a far LOD mesh. Its size: the largest extent of the clips' animated
# bounds, times the instance's scale. lod_auto (the default): the thresholds from what the bake measured
# (the roster's animation_lod), the sizes under which no vertex moves more than LOD_PIXEL_ERROR pixels;
# setting lod gives thresholds of your own (and turns lod_auto off). Vector2.ZERO: every influence at any
# size. lod_reason says which thresholds are in use and why. With the bone pass, an instance under halves_pixels()
# tall (lod not ZERO) skins from the pass's hi halves alone: 3 texel fetches an influence instead of 6 on a GPU (a
# CPU rasteriser runs the masked-off fetches all the same), and the pass draws half its texels, where that moves no
# vertex more than LOD_PIXEL_ERROR pixels (halves_error()). Chosen on the CPU when the camera or a placement changes
# (the pass has no instance transforms), one float an instance.
const LOD_PIXEL_ERROR := 1.0
const FIXED_LOD := Vector2(24, 12) # a roster without animation_lod (older crowdbake): at 24 pixels a pixel is 4% of the animal
@export var lod_auto := true:
	set(value):
		lod_auto = value
		_resolve_lod()
@export var lod := FIXED_LOD:
	set(value):
		lod = value
		if not _resolving_lod:
			lod_auto = false
			lod_reason = "lod = %s as given" % [value]
		_set_lod()
var lod_reason := ""
var _resolving_lod := false
# The bone pass: each instance's bones blended once a frame into a texture (a SubViewport with use_hdr_2d, which
# the web export's Compatibility renderer makes RGBA16F: each float two halves, 6 texels a bone: its affine rows),
# which the mesh then skins from with 6 texel fetches an influence instead of decoding and blending two palette rows
# at every vertex. "auto" (the default): from
# AUTO_BONE_PASS_VERTICES skinned vertices a frame (count x the mesh's vertices), where it was measured to win;
# "always", "never". Read at setup; bone_pass_reason says what and why.
@export_enum("auto", "always", "never") var bone_pass := "auto"
var uses_bone_pass := false
var bone_pass_reason := ""
var _bone_viewport: SubViewport
var _bone_material: ShaderMaterial
var _bone_rect: ColorRect # the pass's quad: both blocks of rows, or the hi halves' alone (_set_far_only)

var time := 0.0 # the herd's clock, seconds (the shader's herd_time)
var palette # the type's CrowdbakePalette
var error := "" # the last failure, one line
var materials: Array[ShaderMaterial] = [] # one per surface drawn: the herd's shader set to its look
var surfaces_merged := 0 # the model's plain-colour surfaces drawn as one (one draw call for them)

var _type := {}
var _data := PackedFloat32Array()
var _states := PackedStringArray()
var _speeds := PackedFloat32Array()
var _texture: ImageTexture
var _dirty := false
var _bounds_dirty := false
var _has_contacts := false # any clip of the type lists contacts (else advance skips the search)
var _places: Array[Transform3D] = [] # place()'s transforms: the travel offset goes on top
var _placed := PackedByteArray() # 1 where place() set the instance's transform
var _lod_size := 0.0 # the animation LOD's measure of the animal: its clips' largest animated extent
# The far tier's inputs when _set_far_tier last marked the instances: it marks them again only when one changed.
var _far_dirty := true # place(), update_bounds() (a caller's own transforms), setup: some instance's placement
var _far_view_projection := Projection()
var _far_unit := -1.0
var _far_lod := Vector2(-1, -1)
var _far_to_world := Transform3D()
var _max_travel := 0.0 # model units: the farthest any row's travel offset puts the body from its placed point
# A CPU rasteriser (SwiftShader under the web export) runs both sides of every `if`, so the far tier's `if` skips no
# fetch there: while every instance is in the far tier (a large herd seen from afar), the materials take a build of
# the shader without the lo-half fetches at all (_herd_shader(true)), 3 fetches an influence instead of 6. And it runs
# a loop until the last vertex of its group leaves it (Cow: 2.5 bones a vertex), so while every instance is also in
# the animation LOD's 1-influence tier (lod.y), they take the build that reads each vertex's largest bone alone, with
# no weights, count or loop (_herd_shader(true, true)): the web runtime's 1-influence tier, drawn as one draw.
var _mixed_shader: Shader
var _far_shader: Shader
var _far_one_shader: Shader
var _far_only := false
var _one_only := false # with _far_only: every instance in the 1-influence tier too (_far_one_shader)
# A renderer compiles a shader's program where it first draws it: the far-only builds are drawn once at setup, each by
# one instance shrunk to a point (_warm_far_builds), so that the herd's first switch to one mid-game costs no compile.
var _warm_ups: Array[MultiMeshInstance3D] = []
var _warm_up_frame := -1 # Engine.get_frames_drawn() when the herd was first drawn with _warm_ups

func _ready() -> void:
	if roster and not animal.is_empty() and mesh and count > 0 and palette == null:
		setup(roster, animal, mesh, count)

func _process(delta: float) -> void:
	if palette == null:
		return
	_retire_warm_up()
	_set_lod() # the camera may have moved
	if playing:
		advance(delta)
	elif _dirty or _bounds_dirty:
		_upload() # what set_state, set_speed and place changed

# Builds the herd: `count` instances of `type` at the origin, in the type's default state at its
# reference speed (playback rate 1), white. false (with `error`) when the type is not in the roster.
func setup(roster_resource: Resource, type: String, skinned_mesh: Mesh, instances: int) -> bool:
	roster = roster_resource
	animal = type
	mesh = skinned_mesh
	count = instances
	if roster == null or not roster.types.has(type):
		return _fail("%s: no animal type '%s' in the roster; see roster.json's types" % [name, type])
	_type = roster.types[type]
	palette = _type["palette"]
	_lod_size = palette.largest_bounds().get_longest_axis_size()
	var heading := 0.0
	for clip in palette.clips:
		heading = maxf(heading, clip.get("travel_heading", Vector3.ZERO).length())
	_max_travel = 0.0
	for r in palette.row_travel:
		_max_travel = maxf(_max_travel, absf(r) * heading)
	_far_dirty = true
	_resolve_lod()
	_has_contacts = _type["clips"].values().any(func(clip): return not clip.get("contacts", []).is_empty())
	_choose_bone_pass()
	var look := _HERD_MESH.build(mesh, _material())
	materials = look["materials"]
	_mixed_shader = materials[0].shader if not materials.is_empty() else null
	_far_shader = _herd_shader(true) if uses_bone_pass else null
	_far_one_shader = _herd_shader(true, true) if uses_bone_pass else null
	_far_only = false
	_one_only = false
	surfaces_merged = look["merged"]
	_set_lod()
	var mm := _new_multimesh(look["mesh"], instances)
	multimesh = mm
	_data.resize(instances * FLOATS)
	_data.fill(0.0)
	_states.resize(instances)
	_speeds.resize(instances)
	_speeds.fill(_type["speed_reference"])
	_places.resize(instances)
	_placed.resize(instances)
	_placed.fill(0)
	for i in instances:
		mm.set_instance_transform(i, Transform3D())
		mm.set_instance_color(i, Color.WHITE)
		if not set_state(i, _type["default_state"], 0.0):
			return false
	update_bounds()
	_build_bone_pass()
	_warm_far_builds(look["mesh"])
	_upload()
	return true

# The herd shader with the palette's layout and precision, its include inlined (so that it also
# resolves outside res://) and every uniform set. far_only: the bone pass's build for a herd whose every instance is
# in the far tier (_set_far_tier switches to it while that holds), which has no lo-half fetches at all.
func _material(far_only := false) -> ShaderMaterial:
	var material := ShaderMaterial.new()
	material.shader = _herd_shader(far_only)
	for key in ["bind_positions", "positions_relative", "row_texels", "rows_per_block", "bounds_min", "bounds_max", "linear_range",
			"local_rows"]:
		material.set_shader_parameter(key, palette.get(key))
	material.set_shader_parameter("palette", palette.texture)
	material.set_shader_parameter("instances_per_row", INSTANCES_PER_ROW)
	return material

func _herd_shader(far_only: bool, one := false) -> Shader:
	return _built(_SHADER, {"CB_BONE_PASS": int(uses_bone_pass), "CB_FAR_ONLY": int(far_only), "CB_ONE_INFLUENCE": int(one)})

# A build of the addon's shader `source`: its includes inlined (so that it also resolves outside res://) and each
# `#define NAME N` line set, for the palette's layout and precision and the other `defines`.
func _built(source: Shader, defines: Dictionary) -> Shader:
	var code := source.code.replace("#include \"crowdbake_palette.gdshaderinc\"", _INCLUDE.code)
	code = code.replace("#include \"crowdbake_bone_pass.gdshaderinc\"", _BONE_PASS_INCLUDE.code)
	defines["CB_LAYOUT"] = ["mat4", "affine", "qpos"].find(palette.layout)
	defines["CB_U16"] = int(palette.precision == "u16")
	for name in defines:
		code = RegEx.create_from_string("(?m)^#define %s \\d+" % name).sub(code, "#define %s %d" % [name, defines[name]])
	var shader := Shader.new()
	shader.code = code
	return shader

# Moves the clock on by `delta` seconds, raising footstep / foot_lifted for every contact an
# instance's clip time crosses, and hands the GPU what changed.
func advance(delta: float) -> void:
	var before := time
	time += delta
	if _has_contacts:
		for i in count:
			_raise_contacts(i, before, time)
	if not palette.row_travel.is_empty():
		for i in count:
			if _placed[i]:
				_draw_placed(i)
	_upload()

# Puts instance `i` into `state` (a state of the roster type), cross-fading from its current clip
# over `fade` seconds (default fade_seconds; 0: at once). A loop starts at the instance's golden-ratio
# phase, a one-shot at its first row.
func set_state(i: int, state: String, fade := -1.0) -> bool:
	var states: Dictionary = _type.get("states", {})
	if not states.has(state) or i < 0 or i >= count:
		return _fail("%s: no state '%s' in type '%s' or no instance %d (states: %s)" % [name, state, animal, i, ", ".join(states.keys())])
	var inst: Dictionary = states[state]["instance"]
	var at := i * FLOATS
	for k in 4:
		_data[at + 4 + k] = _data[at + k] # the previous clip fades out
	_data[at + 8] = time
	_data[at + 9] = fade_seconds if fade < 0.0 else fade
	if _states[i].is_empty():
		_data[at + 9] = 0.0
	_states[i] = state
	var frames := float(inst["frame_count"])
	var rate := _rate(i, state)
	var start := fmod(i * GOLDEN, 1.0) if frames > 0.0 and inst.get("phase") == "golden_ratio" else 0.0
	_data[at] = inst["first_row"]
	_data[at + 1] = frames
	_data[at + 2] = rate
	_data[at + 3] = _wrap(start - time * absf(rate) / absf(frames), frames)
	_dirty = true
	return true

# Ground speed of instance `i` in metres per second: a state that follows speed plays at
# rate_per_speed x speed / scale rows per second (rate = speed / (scale x speed_reference) times its
# own), so the feet stay planted at any uniform scale; the pose does not jump.
func set_speed(i: int, speed: float) -> void:
	_speeds[i] = speed
	_retime(i)

# Instance `i`'s transform in the herd (a uniform scale is the animal's size); keeps the feet (rate)
# in step, and the bounds by the next frame (or update_bounds()).
func place(i: int, xform: Transform3D) -> void:
	_places[i] = xform
	_placed[i] = 1
	_draw_placed(i)
	_retime(i)
	_bounds_dirty = true
	_far_dirty = true

# Instance `i`'s per-row travel offset now, in the model's frame: where the body of a clip with
# offsets is drawn relative to a point moving at the state's speed (cross-fades mix the two clips'
# offsets as the shader mixes their poses). Zero at standstill, in a state that does not follow the
# speed, and for palettes without offsets. place() adds it; a caller setting the multimesh's
# transforms itself adds xform * travel_offset(i).
func travel_offset(i: int) -> Vector3:
	var inst: Dictionary = _type["states"][_states[i]]["instance"] if not _states[i].is_empty() else {}
	if palette.row_travel.is_empty() or float(inst.get("rate_per_speed", 0.0)) == 0.0 or _speeds[i] <= 0.0:
		return Vector3.ZERO
	var to: Vector3 = palette.travel_offset_at(instance_numbers(i), time)
	var fade := _fade(i)
	return to if fade >= 1.0 else palette.travel_offset_at(instance_numbers(i, true), time).lerp(to, fade)

func _draw_placed(i: int) -> void:
	var xform := _places[i]
	multimesh.set_instance_transform(i, Transform3D(xform.basis, xform * travel_offset(i)))

func set_color(i: int, color: Color) -> void:
	multimesh.set_instance_color(i, color)

func get_state(i: int) -> String:
	return _states[i]

# The four numbers instance `i` plays (first row, frame count, rows per second, phase).
func instance_numbers(i: int, previous := false) -> Vector4:
	var at := i * FLOATS + (4 if previous else 0)
	return Vector4(_data[at], _data[at + 1], _data[at + 2], _data[at + 3])

# Bone `bone`'s skinning matrix for instance `i` now, in the herd's space (its instance transform
# applied): the pose the shader draws, cross-fade included (the shader mixes skinned points, which is
# the matrices' mix).
func bone_transform_at(i: int, bone: int) -> Transform3D:
	var m: Transform3D = palette.matrix_at(instance_numbers(i), time, bone)
	var fade := _fade(i)
	if fade < 1.0:
		var m0: Transform3D = palette.matrix_at(instance_numbers(i, true), time, bone)
		m = Transform3D(Basis(m0.basis.x.lerp(m.basis.x, fade), m0.basis.y.lerp(m.basis.y, fade), m0.basis.z.lerp(m.basis.z, fade)),
				m0.origin.lerp(m.origin, fade))
	return multimesh.get_instance_transform(i) * m

# A named socket of the manifest (a prop's node under a joint) for instance `i`, in the herd's space;
# null when the type has no such socket.
func socket_transform(i: int, socket: String):
	var s = _type.get("sockets", {}).get(socket)
	if s == null:
		_fail("%s: no socket '%s' in type '%s' (sockets: %s)" % [name, socket, animal, ", ".join(_type.get("sockets", {}).keys())])
		return null
	return bone_transform_at(i, s["bone"]) * s["transform"]

# The herd's bounds: every instance's box around the largest of the clips' animated bounds (the
# .pal clip table), so Godot culls the herd as a whole and never clips a walking animal. A caller that sets the
# multimesh's transforms itself calls it after (it also has the bone pass's far tier measured again).
func update_bounds() -> void:
	_far_dirty = true
	var clip_box: AABB = palette.largest_bounds()
	var box := AABB()
	for i in count:
		var b := multimesh.get_instance_transform(i) * clip_box
		box = b if i == 0 else box.merge(b)
	multimesh.custom_aabb = box
	_bounds_dirty = false

func _fade(i: int) -> float:
	var at := i * FLOATS
	return clampf((time - _data[at + 8]) / _data[at + 9], 0.0, 1.0) if _data[at + 9] > 0.0 else 1.0

# Rows per second of instance i's state at its speed and scale; a timed state's (rate < 0) cells per second,
# negated, and never -0 (docs/roster.md). A state follows the speed when rate_per_speed != 0 (a timed one's < 0).
func _rate(i: int, state: String) -> float:
	var inst: Dictionary = _type["states"][state]["instance"]
	var per_speed := float(inst.get("rate_per_speed", 0.0))
	if per_speed == 0.0:
		return inst["rate"]
	var scale := multimesh.get_instance_transform(i).basis.get_scale().x
	var rate := absf(per_speed) * _speeds[i] / scale
	return -maxf(rate, TIMED_STILL_RATE) if float(inst["rate"]) < 0.0 else rate

# A new rate for instance i with its clip position kept: the phase takes up the difference.
func _retime(i: int) -> void:
	if _states[i].is_empty():
		return
	var at := i * FLOATS
	var frames := absf(_data[at + 1])
	var fpos := time * absf(_data[at + 2]) + _data[at + 3] * frames # a timed clip's rate is negative: |z| (the shader's)
	var rate := _rate(i, _states[i])
	_data[at + 2] = rate
	_data[at + 3] = _wrap((fpos - time * absf(rate)) / frames, _data[at + 1])
	_dirty = true

static func _wrap(phase: float, frames: float) -> float:
	return fposmod(phase, 1.0) if frames > 0.0 else phase

# The footsteps of instance i's current clip whose times lie in (before, after].
func _raise_contacts(i: int, before: float, after: float) -> void:
	var clip: Dictionary = _type["clips"].get(_type["states"][_states[i]]["clip"], {})
	var contacts: Array = clip.get("contacts", [])
	if contacts.is_empty():
		return
	var inst := instance_numbers(i)
	var frames := absf(inst.y)
	# A timed clip's instance (z < 0) counts cells, its contacts at cell time x cells / duration (crowdbake_contacts.mjs).
	var fps := frames / float(clip["duration"]) if inst.z < 0.0 else float(clip.get("fps", 0.0))
	var f0 := before * absf(inst.z) + inst.w * frames
	var f1 := after * absf(inst.z) + inst.w * frames
	for c in contacts:
		for key in ["time", "lift"]:
			if not c.has(key):
				continue
			var at: float = float(c[key]) * fps # the contact's row (or cell)
			var times := _crossings(at, f0, f1, frames, inst.y > 0.0)
			for n in times:
				if key == "time":
					footstep.emit(i, c.get("foot", ""), int(c.get("bone", -1)))
				else:
					foot_lifted.emit(i, c.get("foot", ""), int(c.get("bone", -1)))

# How often a clip at row position f0 -> f1 passes row `at`: a loop every `frames` rows, a one-shot once.
static func _crossings(at: float, f0: float, f1: float, frames: float, loops: bool) -> int:
	if loops:
		return int(floorf((f1 - at) / frames) - floorf((f0 - at) / frames))
	return 1 if f0 < at and at <= f1 else 0

# The instance texture: three RGBA32F texels per instance.
func _upload() -> void:
	if _bounds_dirty:
		update_bounds()
	if not _dirty and _texture != null:
		_set_all("herd_time", time)
		return
	var rows := maxi(1, ceili(float(count) / INSTANCES_PER_ROW))
	var texels := PackedFloat32Array()
	texels.resize(rows * INSTANCES_PER_ROW * FLOATS)
	for k in _data.size():
		texels[k] = _data[k]
	var image := Image.create_from_data(INSTANCES_PER_ROW * FLOATS / 4, rows, false, Image.FORMAT_RGBAF, texels.to_byte_array())
	if _texture != null and _texture.get_size() == Vector2(image.get_size()):
		_texture.update(image)
	else:
		_texture = ImageTexture.create_from_image(image)
		_set_all("instances", _texture)
	_set_all("herd_time", time)
	_dirty = false

# lod_auto: the thresholds from the roster's animation_lod (a tier's worst vertex error, model units) and
# the measure of the animal: at size S for an error e, S / e pixels tall moves a vertex one pixel.
func _resolve_lod() -> void:
	if not lod_auto or _type.is_empty():
		return
	var measured: Dictionary = _type.get("animation_lod", {})
	var one := float(measured.get("one_influence_error", 0.0))
	var two := float(measured.get("two_influences_error", 0.0))
	var pixels := func(e: float) -> float: return LOD_PIXEL_ERROR * _lod_size / e if e > 0.0 else 1e6
	_resolving_lod = true
	if measured.is_empty() or _lod_size <= 0.0:
		lod = FIXED_LOD
		lod_reason = "lod_auto: the roster has no animation_lod (an older crowdbake): the fixed %s" % [FIXED_LOD]
	else:
		lod = Vector2(maxf(pixels.call(two), pixels.call(one)), pixels.call(one))
		lod_reason = ("lod_auto: 2 influences under %.1f pixels tall, 1 under %.1f: there no vertex moves more than %s pixel (the bake's animation_lod: %.4f and %.4f model units over %d frames, the animal %.3f units long); set lod to override; the bone pass's hi halves alone under %.1f"
				% [lod.x, lod.y, LOD_PIXEL_ERROR, two, one, int(measured.get("frames", 0)), _lod_size, halves_pixels()])
	_resolving_lod = false

# The animation LOD's uniforms for the viewport's camera as it is now (none: every influence).
func _set_lod() -> void:
	var camera := get_viewport().get_camera_3d() if is_inside_tree() else null
	if palette == null:
		return
	if camera == null or lod == Vector2.ZERO:
		_set_all("animation_lod", Vector3.ZERO)
		_set_far_tier(Projection(), 0.0)
		return
	var projection := camera.get_camera_projection()
	var unit := _lod_size * 0.5 * get_viewport().get_visible_rect().size.y * projection.y.y
	_set_all("animation_lod", Vector3(unit, lod.x, lod.y))
	var view_projection := projection * Projection(camera.global_transform.affine_inverse())
	_set_all("lod_view_projection", view_projection)
	_set_far_tier(view_projection, unit)

# With the bone pass, each instance's far tier (the instance texture's float 10: 1 under halves_pixels() tall, as the
# shader measures an instance's size for its influences; unit 0: none), and whether every instance is also in the
# 1-influence tier (under lod.y tall: the shader's count at every vertex of it). Measured again only when the camera's
# view-projection, the unit, lod, the herd's transform or some instance's placement changed since the last time (not
# every frame over every instance). A placed instance is measured at its place()'s point, its depth w taken as near as its
# rows' travel offsets (_max_travel, the body's per-row drift from that point, which moves every frame) can bring it,
# so that the tier holds for the drawn body at any row; an instance the caller moved itself, at its transform.
func _set_far_tier(view_projection: Projection, unit: float) -> void:
	if not uses_bone_pass or multimesh == null or _data.size() < count * FLOATS:
		return
	var to_world := global_transform if unit > 0.0 else Transform3D()
	if not _far_dirty and unit == _far_unit and view_projection == _far_view_projection and to_world == _far_to_world \
			and lod == _far_lod:
		return
	_far_dirty = false
	_far_unit = unit
	_far_view_projection = view_projection
	_far_to_world = to_world
	_far_lod = lod
	var under := halves_pixels()
	var w_row := Vector3(view_projection.x.w, view_projection.y.w, view_projection.z.w) # w = w_row . p + w.w
	var far_count := 0
	var one_count := 0
	for i in count:
		var far := 0.0
		if unit > 0.0:
			var model := to_world * (_places[i] if _placed[i] else multimesh.get_instance_transform(i))
			var w := absf((view_projection * Vector4(model.origin.x, model.origin.y, model.origin.z, 1.0)).w)
			if _placed[i]: # |basis d| <= the basis' Frobenius norm x |d|
				w -= w_row.length() * Vector3(model.basis.x.length(), model.basis.y.length(), model.basis.z.length()).length() * _max_travel
			var pixels := unit * model.basis.x.length() / w if w > 0.0 else INF
			far = 1.0 if pixels < under else 0.0
			one_count += int(pixels < lod.y)
		far_count += int(far)
		if _data[i * FLOATS + 10] != far:
			_data[i * FLOATS + 10] = far
			_dirty = true
	_set_far_only(count > 0 and far_count == count, count > 0 and one_count == count)

# The materials' shader: the far-only build while every instance is in the far tier (the instance texture, uploaded
# this same frame, says so for each), its 1-influence build while every instance is in that tier too, else the one
# that reads each instance's tier.
func _set_far_only(far_only: bool, one_only := false) -> void:
	one_only = far_only and one_only
	if (far_only == _far_only and one_only == _one_only) or _mixed_shader == null:
		return
	_far_only = far_only
	_one_only = one_only
	for m in materials:
		m.shader = _far_one_shader if one_only else _far_shader if far_only else _mixed_shader
	if _bone_rect != null: # the lo halves' block is not drawn while no vertex reads it
		_bone_rect.size.y = _bone_viewport.size.y / (2 if far_only else 1)

# The herd's MultiMesh layout, which the warm-up shares so that its program is the herd's variant.
func _new_multimesh(mesh: Mesh, count: int) -> MultiMesh:
	var mm := MultiMesh.new()
	mm.transform_format = MultiMesh.TRANSFORM_3D
	mm.use_colors = true
	mm.mesh = mesh
	mm.instance_count = count
	return mm

# The far-only builds drawn once (each by one instance of the herd's mesh, its transform a point: no pixel, but the
# program compiled, in the same variants as the herd's: MultiMesh, colours, shadows), never culled; _retire_warm_up
# frees them once a frame has been drawn with them.
func _warm_far_builds(herd_mesh: Mesh) -> void:
	for warm_up in _warm_ups:
		warm_up.queue_free()
	_warm_ups.clear()
	_warm_up_frame = -1
	if _far_shader == null:
		return
	var mm := _new_multimesh(herd_mesh, 1)
	mm.set_instance_transform(0, Transform3D(Basis.from_scale(Vector3.ZERO), Vector3.ZERO))
	for shader in [_far_shader, _far_one_shader]:
		var material := ShaderMaterial.new()
		material.shader = shader
		var warm_up := MultiMeshInstance3D.new()
		warm_up.multimesh = mm
		warm_up.material_override = material
		warm_up.cast_shadow = cast_shadow
		warm_up.custom_aabb = AABB(Vector3.ONE * -1e9, Vector3.ONE * 2e9)
		_warm_ups.append(warm_up)
		add_child(warm_up, false, Node.INTERNAL_MODE_BACK)

func _retire_warm_up() -> void:
	if _warm_ups.is_empty():
		return
	if _warm_up_frame < 0:
		if is_visible_in_tree(): # this frame draws them
			_warm_up_frame = Engine.get_frames_drawn()
	elif Engine.get_frames_drawn() > _warm_up_frame:
		for warm_up in _warm_ups:
			warm_up.queue_free()
		_warm_ups.clear()

# A shader parameter of every surface's material (and of the bone pass's, which reads the same instances and clock).
func _set_all(key: String, value) -> void:
	for m in materials:
		m.set_shader_parameter(key, value)
	if _bone_material != null:
		_bone_material.set_shader_parameter(key, value)

func _fail(message: String) -> bool:
	error = message
	push_error(message)
	return false

# The first skinned mesh under `root` (an imported glTF scene, or GLTFDocument.generate_scene's):
# its bone indices are the glTF skin's joints, as the palette's bones are.
static func skinned_mesh_in(root: Node) -> Mesh:
	if root is MeshInstance3D and root.mesh != null and root.mesh.surface_get_format(0) & Mesh.ARRAY_FORMAT_BONES:
		return root.mesh
	for child in root.get_children():
		var found := skinned_mesh_in(child)
		if found != null:
			return found
	return null

# ---- the bone pass (crowdbake_bone_pass.gdshader) ----

# Skinned vertices a frame from which "auto" takes the bone pass, between where it ties and where it wins: measured
# in Godot 4.6's web build on SwiftShader (bench/godot_crowd.py, walking Cows, medians of frames in turns) with the
# 8-bit pass (12 texels an influence), 1 Cow (4,970 vertices) a tie (bone pass 93 ms a frame, per vertex 98), 10 Cows
# (49,700) ahead (269 against 449); the half-float pass (4 or 6 texels an influence) wins by more: 1,000 Cows 5.5 s
# against 13.2 with 6 (the numbers in the addon's README). Below, the pass's SubViewport and 2 KB a Cow buy nothing.
const AUTO_BONE_PASS_VERTICES := 20000
const BONE_TEXTURE_WIDTH := 4096 # texels a row at most (WebGL 2 promises 4096)
const BONE_TEXTURE_ROWS := 4096
const BONE_TEXELS := 6 # RGBA16F texels a bone (crowdbake_bone_pass.gdshaderinc): 3 of hi halves, 3 of lo ones
const BONE_BLOCK_TEXELS := 3 # a bone's texels in each block of rows (hi above, lo below)

# uses_bone_pass and bone_pass_reason for `bone_pass`, `count` and the mesh.
func _choose_bone_pass() -> void:
	var vertices := 0
	for s in mesh.get_surface_count():
		vertices += mesh.surface_get_array_len(s)
	var span: int = palette.bone_names.size() * BONE_BLOCK_TEXELS
	var rows := 2 * ceili(float(count) / maxi(1, BONE_TEXTURE_WIDTH / span))
	if span > BONE_TEXTURE_WIDTH or rows > BONE_TEXTURE_ROWS:
		uses_bone_pass = false
		bone_pass_reason = "no bone pass: %d instances of %d bones need a %d x %d texture, over %d x %d" % [count,
				span / BONE_BLOCK_TEXELS, mini(span, BONE_TEXTURE_WIDTH), rows, BONE_TEXTURE_WIDTH, BONE_TEXTURE_ROWS]
	elif bone_pass != "auto":
		uses_bone_pass = bone_pass == "always"
		bone_pass_reason = "bone_pass = \"%s\"" % bone_pass
	else:
		uses_bone_pass = count * vertices >= AUTO_BONE_PASS_VERTICES
		bone_pass_reason = ("%d skinned vertices a frame (%d x %d) %s %d: %s (bone_pass = \"always\" or \"never\" to choose)"
				% [count * vertices, count, vertices, ">=" if uses_bone_pass else "<", AUTO_BONE_PASS_VERTICES,
				"each bone blended once an instance" if uses_bone_pass else "the bone pass would not pay for its extra pass"])

# The bone pass's SubViewport (an internal child of the herd, drawn before the herd each frame) and its material.
func _build_bone_pass() -> void:
	if _bone_viewport != null:
		_bone_viewport.queue_free()
		_bone_viewport = null
		_bone_material = null
		_bone_rect = null
	if not uses_bone_pass:
		return
	var bones: int = palette.bone_names.size()
	var per_row := maxi(1, BONE_TEXTURE_WIDTH / (bones * BONE_BLOCK_TEXELS))
	var hi_rows := maxi(1, ceili(float(count) / per_row))
	var size := Vector2i(per_row * bones * BONE_BLOCK_TEXELS, 2 * hi_rows)
	var unit := _bone_translation_unit()
	var base := _material() # the palette's uniforms; its code is the pass's
	_bone_material = base
	_bone_material.shader = _built(_BONE_PASS_SHADER, {"CB_LOCAL_ROWS": int(palette.local_rows)})
	_bone_material.set_shader_parameter("bone_count", bones)
	_bone_material.set_shader_parameter("bone_instances_per_row", per_row)
	_bone_material.set_shader_parameter("bone_lo_rows", hi_rows)
	_bone_material.set_shader_parameter("instance_count", count)
	_bone_material.set_shader_parameter("bone_translation_unit", unit)
	_bone_viewport = SubViewport.new()
	_bone_viewport.size = size
	_bone_viewport.use_hdr_2d = true # RGBA16F in the Compatibility renderer (the halves the pass writes)
	_bone_viewport.render_target_update_mode = SubViewport.UPDATE_ALWAYS
	_bone_viewport.transparent_bg = true
	_bone_viewport.disable_3d = true
	_bone_rect = ColorRect.new()
	_bone_rect.size = Vector2(size.x, hi_rows if _far_only else size.y)
	_bone_rect.material = _bone_material
	_bone_viewport.add_child(_bone_rect)
	add_child(_bone_viewport, false, Node.INTERNAL_MODE_BACK)
	for m in materials:
		m.set_shader_parameter("bone_texture", _bone_viewport.get_texture())
		m.set_shader_parameter("bone_count", bones)
		m.set_shader_parameter("bone_instances_per_row", per_row)
		m.set_shader_parameter("bone_lo_rows", hi_rows)
		m.set_shader_parameter("bone_translation_unit", unit)
	_texture = null # _upload hands the instance texture to the pass too

# The most a vertex moves (model units) skinned from the bone pass's hi halves alone (each number of the bone's
# affine rows [L | t] rounded to a half: within 2^-11 of itself): component k of L v + t moves by at most
# 2^-11 (|row k of L| |v| + |t_k|), the point by 2^-11 (sqrt(3) s |v| + |t|) for L = s R; with the rest point's
# image within 2 translation units and the translation within 4 (bone_translation_unit: the animated bounds' reach,
# rounded up to a power of two), under 8 x 2^-11 units (the rotation form this pass once had: 18 x 2^-11), taken as
# 1/64 (check_conformance_gpu.gd measures it on every conformance case).
func halves_error() -> float:
	return _bone_translation_unit() / 64.0

# The pixels tall under which the bone pass's hi halves alone move no vertex more than LOD_PIXEL_ERROR pixels.
func halves_pixels() -> float:
	return LOD_PIXEL_ERROR * _lod_size / halves_error() if palette != null else 0.0

# The model units a translation in the bone texture counts: the power of two at or above the farthest the clips'
# animated bounds reach from the origin, so that a bone's translation is a few units at most at any model scale (a
# half float overflows at 65504) and dividing by it and multiplying back are exact.
func _bone_translation_unit() -> float:
	var box: AABB = palette.largest_bounds()
	var a := box.position.abs()
	var b := box.end.abs()
	var reach := maxf(maxf(a.x, maxf(a.y, a.z)), maxf(b.x, maxf(b.y, b.z)))
	return pow(2.0, ceilf(log(reach) / log(2.0))) if reach > 0.0 and is_finite(reach) else 1.0

# A hidden herd's bone pass is not drawn.
func _notification(what: int) -> void:
	if what == NOTIFICATION_VISIBILITY_CHANGED and _bone_viewport != null:
		_bone_viewport.render_target_update_mode = SubViewport.UPDATE_ALWAYS if is_visible_in_tree() else SubViewport.UPDATE_DISABLED

# Bytes an instance takes on the GPU beside its MultiMesh row (which every way of drawing a herd has): its three
# texels of the instance texture (RGBA32F), and with the bone pass its bones' 6 texels (RGBA16F, 8 bytes) each.
func bytes_per_instance() -> int:
	return 48 + (BONE_TEXELS * 8 * palette.bone_names.size() if uses_bone_pass else 0)
