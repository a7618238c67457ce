# crowdbake_loader.gd - loads crowdbake palettes and the roster manifest into Godot 4 (tested with 4.6;
# needs Image.FORMAT_RGBA16I, the RGBA16UI texture of the default u16 bake).
#
# The addon's resources (load("res://x.pal"), CrowdbakeHerd) are built on it; use it directly to
# fill a MultiMeshInstance3D of your own:
#
#   var loader := CrowdbakeLoader.new()
#   if not loader.load_roster("res://roster/roster.json") \
#           or not loader.fill_herd($Goats, "goat", "wander", 1.4, 200, 30.0):   # a MultiMeshInstance3D
#       print(loader.error)   # one line: the file and the fix
#
# Every layout and precision loads as baked (docs/pal-format.md): u16 as RGBA16UI, decoded by the
# shader; half as RGBAH; float as RGBAF; zstd payloads are decompressed here. Each check is a runtime
# check that stays in release builds: a failure returns false or {}, sets `error` to one line naming
# the file and the fix, and reports it with push_error.
class_name CrowdbakeLoader
extends RefCounted

const GOLDEN := 0.6180339887
const LAYOUTS := ["mat4", "affine", "qpos"]
const PRECISIONS := ["float", "half", "u16"]
const TEXELS_PER_BONE := [4, 3, 2]
const TEXEL_BYTES := [16, 8, 8]
const IMAGE_FORMATS := [Image.FORMAT_RGBAF, Image.FORMAT_RGBAH, Image.FORMAT_RGBA16I]
const MAGIC_HEX := "434250414c0d0a1a" # "CBPAL\r\n\x1a"
const HEADER_SIZE := 256
# The Compatibility renderer (OpenGL, WebGL) stores MultiMesh custom data and colors as half floats
# (Godot 4.6: custom data 3001 reads 3000 in the shader), which hold integers exactly only up to 2048.
const COMPATIBILITY_MAX_ROW := 2048
const BONE_ENTRY_SIZE := 32
const RANGE_ENTRY_SIZE := 32 # version 6's bone range table (local rows): pos_min, scale_max, pos_max, reserved
const LOCAL_ROWS := 32       # header flag bit 5: each row holds a bone in its parent's frame (version 6)

var roster: Dictionary = {}
var error := "" # the last failure, one line
var _dir := ""

func _fail(message: String) -> bool:
	error = message
	push_error(message)
	return false

func load_roster(path: String) -> bool:
	var text := FileAccess.get_file_as_string(path)
	if text.is_empty():
		return _fail("%s: cannot read the roster manifest (%s)" % [path, error_string(FileAccess.get_open_error())])
	var parsed = JSON.parse_string(text)
	if not (parsed is Dictionary and parsed.get("schema") == "crowdbake-roster/1"):
		return _fail("%s is not a crowdbake roster (schema crowdbake-roster/1); give the roster.json that " % path
				+ "`crowdbake bake catalog.toml` wrote")
	roster = parsed
	_dir = path.get_base_dir()
	return true

# Reads a .pal: {texture, image (the texels, for CPU-side lookups), bind_positions, layout, precision,
# row_texels, rows_per_block, bounds_min, bounds_max, linear_range, local_rows}, or {} with `error` set.
func load_palette(path: String) -> Dictionary:
	var f := FileAccess.open(path, FileAccess.READ)
	if f == null:
		_fail("%s: cannot open the palette (%s)" % [path, error_string(FileAccess.get_open_error())])
		return {}
	var file_size := f.get_length()
	var head := f.get_buffer(HEADER_SIZE)
	if head.size() < HEADER_SIZE or head.slice(0, 8).hex_encode() != MAGIC_HEX:
		_fail("%s is not a crowdbake palette (no CBPAL header); bake it with `crowdbake bake MODEL -o FILE.pal`" % path)
		return {}
	var version := head.decode_u32(8)
	var flags := head.decode_u32(12)
	var layout := head.decode_u32(20)
	var precision := head.decode_u32(24)
	if version < 1 or version > 7 or head.decode_u32(16) != HEADER_SIZE:
		_fail("%s: palette format version %d is not supported (this loader reads versions 1 to 7); use the loader of the crowdbake that baked it"
				% [path, version])
		return {}
	if layout > 2 or precision > 2:
		_fail("%s: unknown layout %d or precision %d in the header; the file is damaged, re-bake it" % [path, layout, precision])
		return {}
	var bones := head.decode_u32(32)
	var row_texels := head.decode_u32(36)
	var width := head.decode_u32(44)
	var height := head.decode_u32(48)
	var blocks := head.decode_u32(52)
	var bone_table := head.decode_u64(128)
	# Version 3 qpos/half: each bone's position offset (what its position texels are relative to).
	var offset_table := head.decode_u64(184) if version >= 3 and flags & 4 else 0
	# Version 5: the per-row travel offsets (one float a row), what a herd adds along a clip's heading.
	var travel_table := head.decode_u64(192) if version >= 5 and flags & 16 else 0
	# Version 6: local rows (flag bit 5), each bone's ranges in the bone range table (header byte 200).
	var local_rows := version >= 6 and flags & LOCAL_ROWS != 0
	var range_table := head.decode_u64(200) if local_rows else 0
	# Version 7: timed rows (flag bit 6); crowdbake_palette.gd reads and checks the timed clip table (header byte 208).
	if flags & 64 and version < 7:
		_fail("%s: flag bit 6 (timed rows) in a version %d file; timed rows are version 7, the file is damaged, re-bake it" % [path, version])
		return {}
	if local_rows and (layout != 2 or precision == 1):
		_fail("%s: local rows need qpos and u16 or float, not %s/%s; the file is damaged, re-bake it" % [path, LAYOUTS[layout], PRECISIONS[precision]])
		return {}
	var rows := head.decode_u32(40)
	var payload_offset := head.decode_u64(152)
	var payload_size := head.decode_u64(160)
	var raw_size := head.decode_u64(168)
	# Sizes first, in 64-bit integers, so that a damaged header cannot make a huge allocation or a
	# read past the end: the same checks as include/crowdbake_pal.h (less the checksum).
	if bones == 0 or bones > 65535 or height == 0 or blocks == 0 or head.decode_u32(28) != TEXELS_PER_BONE[layout] \
			or row_texels != bones * TEXELS_PER_BONE[layout] or width != blocks * row_texels \
			or head.decode_u32(56) != TEXEL_BYTES[precision] or raw_size != width * height * TEXEL_BYTES[precision] \
			or bone_table < HEADER_SIZE or bone_table + bones * BONE_ENTRY_SIZE > file_size \
			or (offset_table != 0 and offset_table + bones * 12 > file_size) or (version >= 3 and flags & 4 and offset_table < HEADER_SIZE) \
			or (version >= 5 and flags & 16 and (travel_table < HEADER_SIZE or travel_table + rows * 4 > file_size)) \
			or (local_rows and (range_table < HEADER_SIZE or range_table % 4 != 0 or range_table + bones * RANGE_ENTRY_SIZE > file_size)) \
			or payload_offset < HEADER_SIZE or payload_size < 1 or payload_offset + payload_size > file_size \
			or (flags & 1 == 0 and payload_size != raw_size):
		_fail("%s: the header's sizes do not add up (or the file is truncated to %d bytes); re-bake it" % [path, file_size])
		return {}
	f.seek(payload_offset)
	var payload := f.get_buffer(payload_size)
	if flags & 1:
		payload = payload.decompress(raw_size, FileAccess.COMPRESSION_ZSTD)
		if payload.size() != raw_size:
			_fail("%s: the zstd payload does not decompress to %d bytes; re-bake it" % [path, raw_size])
			return {}
	var image := Image.create_from_data(width, height, false, IMAGE_FORMATS[precision], payload)
	# Row 0: the bind positions (qpos pivots); row 1: the position offsets positions_relative adds
	# (version 3's table; the bind positions in version 2).
	var bind := PackedFloat32Array()
	f.seek(bone_table)
	var table := f.get_buffer(bones * BONE_ENTRY_SIZE)
	for i in bones:
		var at := i * BONE_ENTRY_SIZE
		bind.append_array([table.decode_float(at + 16), table.decode_float(at + 20), table.decode_float(at + 24), 0.0])
	if offset_table != 0:
		f.seek(offset_table)
		var offsets := f.get_buffer(bones * 12)
		for i in bones:
			bind.append_array([offsets.decode_float(i * 12), offsets.decode_float(i * 12 + 4), offsets.decode_float(i * 12 + 8), 0.0])
	else:
		bind.append_array(bind.duplicate())
	if local_rows: # rows 2..4 of the shaders' bone texture: the parent; pos_min, scale_max; pos_max, 0
		f.seek(range_table)
		var local := _local_bone_rows(path, table, f.get_buffer(bones * RANGE_ENTRY_SIZE), bones)
		if local.is_empty():
			return {}
		bind.append_array(local)
	var bind_image := Image.create_from_data(bones, bind.size() / (bones * 4), false, Image.FORMAT_RGBAF, bind.to_byte_array())
	var row_travel := PackedFloat32Array()
	if travel_table != 0:
		f.seek(travel_table)
		row_travel = f.get_buffer(rows * 4).to_float32_array()
	return {
		"texture": ImageTexture.create_from_image(image),
		"image": image,
		"bind_positions": ImageTexture.create_from_image(bind_image),
		"bind": bind, # the same, 4 floats per bone and row, for CPU-side lookups
		"local_rows": local_rows, # version 6 flag bit 5: rows in each bone's parent's frame, composed down its chain
		"row_travel": row_travel, # version 5: each row's travel offset along its clip's heading; else empty
		"positions_relative": 1.0 if flags & 4 else 0.0, # qpos/half: position texels hold p less the offset (row 1)
		"layout": LAYOUTS[layout],
		"precision": PRECISIONS[precision],
		"row_texels": row_texels,
		"rows_per_block": height,
		"linear_range": head.decode_float(72),
		"bounds_min": Vector3(head.decode_float(76), head.decode_float(80), head.decode_float(84)),
		"bounds_max": Vector3(head.decode_float(88), head.decode_float(92), head.decode_float(96)),
	}

# bind_positions rows 2..4 of a file of local rows (docs/pal-format.md, version 6), 12 floats a bone after the
# bone table's parents and the bone range table are checked as include/crowdbake_pal.h checks them (parents in
# range and no chain that loops - the shaders walk each chain to its root; ranges finite, min <= max,
# scale_max > 0, reserved 0); empty with `error` set when one fails.
func _local_bone_rows(path: String, bone_table: PackedByteArray, ranges: PackedByteArray, bones: int) -> PackedFloat32Array:
	var parents := PackedInt32Array()
	for i in bones:
		parents.append(bone_table.decode_s32(i * BONE_ENTRY_SIZE + 8))
	for i in bones:
		var steps := 0
		var p := parents[i]
		while p >= 0 and p < bones and steps <= bones:
			p = parents[p]
			steps += 1
		if p < -1 or p >= bones or steps > bones:
			_fail("%s: bone %d's parent chain leaves the bone table or loops; the file is damaged, re-bake it" % [path, i])
			return PackedFloat32Array()
	var rows := PackedFloat32Array()
	rows.resize(bones * 12)
	for i in bones:
		var at := i * RANGE_ENTRY_SIZE
		var low := Vector3(ranges.decode_float(at), ranges.decode_float(at + 4), ranges.decode_float(at + 8))
		var scale_max := ranges.decode_float(at + 12)
		var high := Vector3(ranges.decode_float(at + 16), ranges.decode_float(at + 20), ranges.decode_float(at + 24))
		if not (low.is_finite() and high.is_finite() and is_finite(scale_max)) or scale_max <= 0.0 \
				or low.x > high.x or low.y > high.y or low.z > high.z or ranges.decode_u32(at + 28) != 0:
			_fail("%s: bone %d's entry of the bone range table is not finite, min > max or scale_max <= 0; the file is damaged, re-bake it" % [path, i])
			return PackedFloat32Array()
		rows[i * 4] = float(parents[i])
		rows[(bones + i) * 4] = low.x
		rows[(bones + i) * 4 + 1] = low.y
		rows[(bones + i) * 4 + 2] = low.z
		rows[(bones + i) * 4 + 3] = scale_max
		rows[(2 * bones + i) * 4] = high.x
		rows[(2 * bones + i) * 4 + 1] = high.y
		rows[(2 * bones + i) * 4 + 2] = high.z
	return rows

# The value of `#define NAME n` in a shader's source, or -1.
static func _shader_define(code: String, name: String) -> int:
	var found := RegEx.create_from_string("(?m)^\\s*#define\\s+%s\\s+(\\d+)" % name).search(code)
	return found.get_string(1).to_int() if found else -1

# Sets a ShaderMaterial using crowdbake_crowd*.gdshader to a palette from load_palette(); false (with
# `error`) when the shader's CB_LAYOUT / CB_U16 defines do not match the palette.
func apply_palette(material: ShaderMaterial, pal: Dictionary, what: String) -> bool:
	if material == null or material.shader == null:
		return _fail("%s: give it a ShaderMaterial with crowdbake_crowd.gdshader as its material override" % what)
	var layout: int = LAYOUTS.find(pal["layout"])
	var u16 := 1 if pal["precision"] == "u16" else 0
	var code := material.shader.code
	if _shader_define(code, "CB_LAYOUT") != layout or _shader_define(code, "CB_U16") != u16:
		return _fail("%s: the palette is %s/%s; set `#define CB_LAYOUT %d` and `#define CB_U16 %d` at the top of %s" %
				[what, pal["layout"], pal["precision"], layout, u16, material.shader.resource_path])
	for name in ["bind_positions", "positions_relative", "row_texels", "rows_per_block", "local_rows"]:
		material.set_shader_parameter(name, pal[name])
	material.set_shader_parameter("palette", pal["texture"])
	if u16:
		for name in ["bounds_min", "bounds_max", "linear_range"]:
			material.set_shader_parameter(name, pal[name])
	return true

# Points a MultiMeshInstance3D (its mesh skinned, material = crowdbake_crowd.gdshader) at a type's
# palette and fills `count` instances in `state` at ground speed `speed`, spread over a square.
func fill_herd(node: MultiMeshInstance3D, type: String, state: String, speed: float, count: int, spread: float) -> bool:
	var t: Dictionary = roster.get("types", {}).get(type, {})
	if t.is_empty() or not t.get("states", {}).has(state):
		return _fail("%s: no animal type '%s' with state '%s' in the roster; see roster.json's types" % [node.name, type, state])
	var pal := load_palette(_dir.path_join(t["palette"]))
	if pal.is_empty() or not apply_palette(node.material_override as ShaderMaterial, pal, node.name):
		return false
	var inst: Dictionary = t["states"][state]["instance"]
	if RenderingServer.get_current_rendering_method() == "gl_compatibility" \
			and (inst["first_row"] > COMPATIBILITY_MAX_ROW or absi(inst["frame_count"]) > COMPATIBILITY_MAX_ROW):
		return _fail(("%s: state '%s' of '%s' starts at palette row %d; the Compatibility renderer keeps instance data as "
				+ "half floats, exact only up to row %d: use Forward+ or Mobile, or give that type fewer clips")
				% [node.name, state, type, inst["first_row"], COMPATIBILITY_MAX_ROW])
	# A state follows the speed when rate_per_speed != 0; a timed state's rate (< 0, cells per second) stays negative,
	# -1e-30 standing still, never -0 (docs/roster.md; crowdbake_pal.mjs instanceData).
	var rate: float = inst["rate"] if inst["rate_per_speed"] == 0.0 else absf(inst["rate_per_speed"]) * speed
	if inst["rate"] < 0.0 and inst["rate_per_speed"] != 0.0:
		rate = -maxf(rate, 1e-30)
	var mm := MultiMesh.new()
	mm.transform_format = MultiMesh.TRANSFORM_3D
	mm.use_custom_data = true
	mm.mesh = node.multimesh.mesh if node.multimesh else null
	mm.instance_count = count
	for i in count:
		var at := Vector3(randf_range(-spread, spread), 0.0, randf_range(-spread, spread))
		mm.set_instance_transform(i, Transform3D(Basis(Vector3.UP, randf() * TAU), at))
		var phase := fmod(i * GOLDEN, 1.0) if inst["phase"] == "golden_ratio" else 0.0
		mm.set_instance_custom_data(i, Color(inst["first_row"], inst["frame_count"], rate, phase))
	node.multimesh = mm
	return true
