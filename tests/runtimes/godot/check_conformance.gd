# check_conformance.gd - the runtime conformance cases (runtimes/README.md, tests/runtimes/conformance.h) with the
# addon's CPU path in Godot 4.6's web build, run by check_addon.gd (whose case lines it prints). For every case
# that is neither broken nor a bone pass, CrowdbakePalette.matrix_at gives each bone of each instance of the first
# group, every vertex is skinned with its four joints and weights, and the worst |got - expected| against the C
# runtime's CASE.expected must stay within 1e-5 x max(1, model height); the broken case "broken-row-off-by-one"
# (rows one off in cases.json's instances) must miss by more than ten times that, which shows the comparison can
# fail. Every instance and vertex of the group is checked (no subset): the meshes are small enough.
extends RefCounted

const ROOT := "/crowdbake"
const ADDON := ROOT + "/addons/crowdbake"
const DIR := ROOT + "/bakes/conformance"
const BROKEN := ["broken-row-off-by-one", "broken-timed-map-ignored"] # faults in the instances, which the addon plays

var addon # check_addon.gd's instance: _begin, _end

func _init(addon_check) -> void:
	addon = addon_check

func run() -> void:
	var cases: Array = JSON.parse_string(FileAccess.get_file_as_string(DIR + "/cases.json"))["cases"]
	# Local rows (.pal version 6) once the addon composes them (its `local_rows`, docs/pal-format.md).
	var composes := FileAccess.get_file_as_string(ADDON + "/crowdbake_palette.gd").contains("local_rows")
	for c in cases:
		if c.get("local", false) and not composes:
			continue
		if c.has("bone_pass") or (c["broken"] and not (c["name"] in BROKEN)):
			continue # the bone pass is the shaders'; the other faults live in shader code or storage
		_check_case(c)

# One case: the first group's instances skinned on the CPU against the first part of CASE.expected.
func _check_case(c: Dictionary) -> void:
	var pal = load(ADDON + "/crowdbake_palette.gd").new()
	if not pal.load_file(DIR + "/" + c["pal"]):
		addon._begin("conformance " + c["name"])
		return addon._end("conformance " + c["name"], pal.error)
	var height := FileAccess.get_file_as_bytes(DIR + "/" + c["pal"]).decode_float(104) # the header's model_height
	var tolerance := 1e-5 * maxf(1.0, height)
	var positions := FileAccess.get_file_as_bytes(DIR + "/" + c["mesh"]["positions"]).to_float32_array()
	var joints := FileAccess.get_file_as_bytes(DIR + "/" + c["mesh"]["joints"])
	var weights := FileAccess.get_file_as_bytes(DIR + "/" + c["mesh"]["weights"]).to_float32_array()
	var expected := FileAccess.get_file_as_bytes(DIR + "/" + c["expected"]).to_float32_array()
	var group: Dictionary = c["groups"][0]
	var time: float = group["time"]
	var verts := positions.size() / 3
	var worst := 0.0
	var at := 0
	for v in group["instances"]:
		var to := _skin(pal, Vector4(v[4], v[5], v[6], v[7]), time, positions, joints, weights)
		var fade := clampf((time - v[12]) / v[13], 0.0, 1.0) if v[13] > 0.0 else 1.0
		if fade < 1.0 and pal.local_rows: # local rows fade bone by bone before they are composed
			to = _skin_faded(pal, Vector4(v[8], v[9], v[10], v[11]), Vector4(v[4], v[5], v[6], v[7]), fade, time, positions,
					joints, weights)
		elif fade < 1.0: # blending positions linearly is blending the bones linearly
			var from := _skin(pal, Vector4(v[8], v[9], v[10], v[11]), time, positions, joints, weights)
			for i in verts:
				to[i] = from[i].lerp(to[i], fade)
		for i in verts:
			var want := Vector3(expected[at], expected[at + 1], expected[at + 2])
			var d := (to[i] - want).abs()
			worst = maxf(worst, maxf(d.x, maxf(d.y, d.z)))
			at += 3
	var ratio := worst / tolerance
	var name := "conformance %s: worst %s (%s of the tolerance)" % [c["name"], String.num_scientific(worst), String.num(ratio, 3)]
	addon._begin(name)
	var why := ""
	if c["broken"] and ratio <= 10.0:
		why = "the broken case came within %s of the tolerance" % ratio
	elif not c["broken"] and ratio > 1.0:
		why = "worst %s, tolerance %s" % [worst, tolerance]
	addon._end(name, why)

# Every vertex skinned by one instance at `time`: the sum of its four joints' matrices x weights.
static func _skin(pal, inst: Vector4, time: float, positions: PackedFloat32Array, joints: PackedByteArray,
		weights: PackedFloat32Array) -> PackedVector3Array:
	var bones: Array[Transform3D] = []
	for bone in pal.bone_names.size():
		bones.append(pal.matrix_at(inst, time, bone))
	return _skin_by(bones, positions, joints, weights)

# The same cross-faded from instance `from` by the addon's matrix_crossfade_at (local rows: the fade per bone).
static func _skin_faded(pal, from: Vector4, inst: Vector4, fade: float, time: float, positions: PackedFloat32Array,
		joints: PackedByteArray, weights: PackedFloat32Array) -> PackedVector3Array:
	var bones: Array[Transform3D] = []
	for bone in pal.bone_names.size():
		bones.append(pal.matrix_crossfade_at(from, inst, fade, time, bone))
	return _skin_by(bones, positions, joints, weights)

static func _skin_by(bones: Array[Transform3D], positions: PackedFloat32Array, joints: PackedByteArray,
		weights: PackedFloat32Array) -> PackedVector3Array:
	var out := PackedVector3Array()
	out.resize(positions.size() / 3)
	for i in out.size():
		var p := Vector3(positions[i * 3], positions[i * 3 + 1], positions[i * 3 + 2])
		var sum := Vector3.ZERO
		for k in 4:
			var w := weights[i * 4 + k]
			if w != 0.0:
				sum += w * (bones[joints.decode_u16(i * 8 + k * 2)] * p)
		out[i] = sum
	return out
