# crowdbake_palette.gd - a crowdbake .pal as a Godot resource: the texture the shaders read, the
# header's numbers, the clip table (with each clip's animated bounds) and the bones, plus the CPU side
# of the shader's skinning: bone_matrix(clip, time, bone), blended exactly as the shaders blend rows.
#
#   var pal: CrowdbakePalette = load("res://roster/cow.pal")   # crowdbake_format_loader.gd
#   var m: Transform3D = pal.bone_matrix("AnimalArmature|Walk", 0.4, pal.bone_index("Head"))
#
# The loading and its checks are crowdbake_loader.gd's (load_palette); this adds the tables. Every
# field is stored (@export_storage, Godot 4.3+): the editor's import (crowdbake_import_palette.gd)
# saves a loaded palette as a resource, which loads back whole in the editor and in exported games.
@tool
class_name CrowdbakePalette
extends Resource

const _Loader := preload("crowdbake_loader.gd")
const CLIP_ENTRY_SIZE := 80
const TIMED_ENTRY_SIZE := 16 # version 7's timed clip table (header byte 208): cells, cell_rate, map_rows, reserved
const TIMED_ROWS := 64       # header flag bit 6 (version 7): some clip's rows are timed (clip flag bit 3, 8)

@export_storage var texture: ImageTexture          # the payload as baked: RGBA16UI (u16), RGBAH (half) or RGBAF (float)
@export_storage var bind_positions: ImageTexture   # row 0 the bones' bind positions, row 1 their position offsets
                                                   # (local rows: rows 2..4, the parents and each bone's ranges)
@export_storage var local_rows := false            # version 6 flag bit 5: rows hold each bone in its parent's frame
@export_storage var positions_relative := 0.0
@export_storage var layout := ""                   # mat4, affine, qpos
@export_storage var precision := ""                # float, half, u16
@export_storage var row_texels := 0
@export_storage var rows_per_block := 0
@export_storage var linear_range := 0.0
@export_storage var bounds_min := Vector3.ZERO
@export_storage var bounds_max := Vector3.ZERO
@export_storage var speed_reference := 0.0         # ground speed (m/s) at playback rate 1; 0 when unset
# One Dictionary per clip: name, first_row, frames, fps (rows per second of clip time), duration,
# loops, step (rows held, not blended: a STEP-keyed clip, .pal version 4), bounds (AABB of the
# skinned mesh over the clip), travel_heading (version 5: the direction its rows' travel offsets lie
# along; zero without them), timed, cells, cell_rate (version 7: a timed clip's rows lie on a grid of `cells`
# steps, `cell_rate` a second, and its map, in the rows just before first_row, says which two rows each cell
# blends; false, 0, 0 otherwise).
@export_storage var clips: Array[Dictionary] = []
@export_storage var row_travel := PackedFloat32Array() # version 5: per row, the body's offset along its clip's heading
@export_storage var bone_names := PackedStringArray()
var error := "" # the last failure, one line

@export_storage var _payload := PackedByteArray() # the texels, for bone_matrix
@export_storage var _bind := PackedFloat32Array() # 4 floats per bone: row 0, row 1 (local rows: to row 4) of bind_positions
@export_storage var _width := 0
@export_storage var _texel_bytes := 0
@export_storage var _texels_per_bone := 0

# Reads `path` into this resource; false (with `error`) when the file is refused.
func load_file(path: String) -> bool:
	var loader := _Loader.new()
	var pal: Dictionary = loader.load_palette(path)
	if pal.is_empty():
		error = loader.error
		return false
	for key in ["texture", "bind_positions", "positions_relative", "layout", "precision", "row_texels",
			"rows_per_block", "linear_range", "bounds_min", "bounds_max", "local_rows"]:
		set(key, pal[key])
	var image: Image = pal["image"]
	_payload = image.get_data()
	_width = image.get_width()
	_texels_per_bone = _Loader.TEXELS_PER_BONE[_Loader.LAYOUTS.find(layout)]
	_texel_bytes = _Loader.TEXEL_BYTES[_Loader.PRECISIONS.find(precision)]
	_bind = pal["bind"]
	row_travel = pal["row_travel"]
	return _read_tables(path)

# The clip table and the bone names from the string table (load_palette checked the header's sizes).
func _read_tables(path: String) -> bool:
	var bytes := FileAccess.get_file_as_bytes(path)
	var clip_count := bytes.decode_u32(60)
	var clip_table := bytes.decode_u64(120)
	var bone_table := bytes.decode_u64(128)
	var strings := bytes.decode_u64(136)
	var strings_size := bytes.decode_u64(144)
	speed_reference = bytes.decode_float(68)
	if clip_table < 256 or clip_table + clip_count * CLIP_ENTRY_SIZE > bytes.size() or strings + strings_size > bytes.size():
		error = "%s: the clip table or the string table lies past the end of the file; re-bake it" % path
		push_error(error)
		return false
	var text := func(at: int) -> String:
		var offset := bytes.decode_u32(at)
		return bytes.slice(strings + offset, strings + offset + bytes.decode_u32(at + 4)).get_string_from_utf8()
	var version := bytes.decode_u32(8)
	var timed_table := bytes.decode_u64(208) if version >= 7 and bytes.decode_u32(12) & TIMED_ROWS else 0
	if timed_table != 0 and (timed_table < 256 or timed_table % 4 != 0 or timed_table + clip_count * TIMED_ENTRY_SIZE > bytes.size()):
		return _refuse("%s: the timed clip table (offset %d, %d clips) lies outside the file; re-bake it" % [path, timed_table, clip_count])
	for i in clip_count:
		var at := clip_table + i * CLIP_ENTRY_SIZE
		var low := Vector3(bytes.decode_float(at + 44), bytes.decode_float(at + 48), bytes.decode_float(at + 52))
		var high := Vector3(bytes.decode_float(at + 56), bytes.decode_float(at + 60), bytes.decode_float(at + 64))
		clips.append({"name": text.call(at), "first_row": bytes.decode_u32(at + 8), "frames": bytes.decode_u32(at + 12),
				"fps": bytes.decode_float(at + 16), "duration": bytes.decode_float(at + 20),
				"loops": bytes.decode_u32(at + 28) & 1 == 1, "step": bytes.decode_u32(at + 28) & 4 == 4,
				"bounds": AABB(low, high - low), "travel_heading": Vector3(bytes.decode_float(at + 68),
				bytes.decode_float(at + 72), bytes.decode_float(at + 76)) if not row_travel.is_empty() else Vector3.ZERO,
				"timed": bytes.decode_u32(at + 28) & 8 == 8, "cells": 0, "cell_rate": 0.0})
		if not _read_timed(path, bytes, timed_table, i):
			return false
	for i in bytes.decode_u32(32):
		bone_names.append(text.call(bone_table + i * _Loader.BONE_ENTRY_SIZE))
	return true

func _refuse(message: String) -> bool:
	error = message
	push_error(error)
	return false

# Clip i's timed entry (docs/pal-format.md "Timed rows"): clip flag bit 3 if and only if a nonzero entry; cells >= 1,
# cell_rate > 0 and finite, map_rows = ceil(cells / row_texels) <= first_row, reserved 0; every map texel's rows whole
# and below the clip's frames, its weights 0 <= f0 <= f1 <= 1 (include/crowdbake_pal.h's checks).
func _read_timed(path: String, bytes: PackedByteArray, table: int, i: int) -> bool:
	var c: Dictionary = clips[i]
	if table == 0:
		return not c["timed"] or _refuse("%s: clip %d (%s) is timed in a file without timed rows (flag bit 6); re-bake it" % [path, i, c["name"]])
	var at := table + i * TIMED_ENTRY_SIZE
	var cells := bytes.decode_u32(at)
	var rate := bytes.decode_float(at + 4)
	var map_rows := bytes.decode_u32(at + 8)
	var entry := cells != 0 or bytes.decode_u32(at + 4) != 0 or map_rows != 0 or bytes.decode_u32(at + 12) != 0
	if entry != c["timed"]:
		return _refuse("%s: clip %d (%s): timed flag and timed table entry disagree; re-bake it" % [path, i, c["name"]])
	if not entry:
		return true
	if cells < 1 or not (rate > 0.0) or is_inf(rate) or bytes.decode_u32(at + 12) != 0 \
			or map_rows != (cells + row_texels - 1) / row_texels or map_rows > c["first_row"]:
		return _refuse("%s: clip %d (%s): bad timed entry (%d cells at %s a second, %d map rows); re-bake it" % [path, i, c["name"], cells, rate, map_rows])
	c["cells"] = cells
	c["cell_rate"] = rate
	for cell in cells:
		var m := _map_texel(c["first_row"], cells, cell)
		if not (m.x >= 0.0 and m.x < c["frames"] and m.x == floorf(m.x) and m.y >= 0.0 and m.y < c["frames"] and m.y == floorf(m.y) \
				and m.z >= 0.0 and m.z <= m.w and m.w <= 1.0):
			return _refuse("%s: clip %d (%s): its map's cell %d reads %s; re-bake it" % [path, i, c["name"], cell, m])
	return true

# A clip's index by name (or an index passed through), -1 when there is none.
func clip_index(clip) -> int:
	if clip is int:
		return clip if clip >= 0 and clip < clips.size() else -1
	for i in clips.size():
		if clips[i]["name"] == clip:
			return i
	return -1

func bone_index(bone_name: String) -> int:
	return bone_names.find(bone_name)

# The four numbers the shaders take for a clip played at its own rate (rows per second; a timed clip: cells per
# second) from `phase` (cb_instance_of): a timed clip's (first row, +-cells, -cell_rate, phase), negative marking it.
func clip_instance(clip: int, rate := -1.0, phase := 0.0) -> Vector4:
	var c: Dictionary = clips[clip]
	var first: float = -c["first_row"] - 1.0 if c["step"] else c["first_row"] # held rows: negative
	if c["timed"]:
		return Vector4(first, c["cells"] if c["loops"] else -c["cells"], -(c["cell_rate"] if rate < 0.0 else rate), phase)
	return Vector4(first, c["frames"] if c["loops"] else -c["frames"], c["fps"] if rate < 0.0 else rate, phase)

# The largest of the clips' animated bounds: a box every animated vertex of any clip stays in.
func largest_bounds() -> AABB:
	var box := AABB()
	for i in clips.size():
		box = clips[i]["bounds"] if i == 0 else box.merge(clips[i]["bounds"])
	return box

# Bone `bone`'s skinning matrix (the glTF joint matrix, global(joint) x inverse bind) `time` seconds
# into `clip` (a name or an index; loops wrap, one-shots clamp), blended as the shaders blend rows;
# null (with `error`) for a clip or bone that does not exist.
func bone_matrix(clip, time: float, bone: int):
	var index := clip_index(clip)
	if index < 0 or bone < 0 or bone >= bone_names.size():
		error = "bone_matrix: no clip %s or no bone %d in this palette (%d clips, %d bones)" % [clip, bone, clips.size(), bone_names.size()]
		push_error(error)
		return null
	return matrix_at(clip_instance(index), time, bone)

# The skinning matrix of `bone` for an instance's four numbers at `time`: cb_frame, then cb_bone (local rows:
# composed down the bone's chain).
func matrix_at(inst: Vector4, time: float, bone: int) -> Transform3D:
	var frame := frame_at(inst, time)
	if local_rows:
		return _composed(frame, frame, 1.0, bone)
	return _blend(frame[0], frame[1], frame[2], bone)

# The skinning matrix of `bone` cross-faded from instance `from` (fade 0) to `inst` (fade 1) at `time`, as the
# shaders fade: global rows, the two matrices blended linearly; local rows, each bone's two blended local rows
# blended again (nlerp, lerp) before they are composed.
func matrix_crossfade_at(from: Vector4, inst: Vector4, fade: float, time: float, bone: int) -> Transform3D:
	var frame := frame_at(inst, time)
	var from_frame := frame_at(from, time)
	if local_rows:
		return _composed(frame, from_frame, fade, bone)
	var a := _blend(from_frame[0], from_frame[1], from_frame[2], bone)
	var b := _blend(frame[0], frame[1], frame[2], bone)
	return Transform3D(Basis(a.basis.x.lerp(b.basis.x, fade), a.basis.y.lerp(b.basis.y, fade), a.basis.z.lerp(b.basis.z, fade)),
			a.origin.lerp(b.origin, fade))

# The body's travel offset (.pal version 5) for an instance's four numbers at `time`, in the model's
# frame: the rows' offsets blended as the shaders blend the rows, along the clip's heading. A herd
# that moves the instance at the clip's ground speed draws it there (cbpal_travel_offset's numbers);
# zero for clips and palettes without offsets.
func travel_offset_at(inst: Vector4, time: float) -> Vector3:
	if row_travel.is_empty():
		return Vector3.ZERO
	var frame := frame_at(inst, time)
	var first := -inst.x - 1.0 if inst.x < 0.0 else inst.x
	for c in clips:
		if c["first_row"] == int(first) and frame[1] < row_travel.size():
			return c["travel_heading"] * lerpf(row_travel[frame[0]], row_travel[frame[1]], frame[2])
	return Vector3.ZERO

# cb_frame of crowdbake_palette.gdshaderinc: [row0, row1, weight of row1]. inst.y counts rows, or with inst.z < 0
# (a timed clip, .pal version 7) the cells of its grid at -inst.z a second: the cell's map texel names the two rows
# and the weight runs from its f0 to its f1 across the cell (cb_runtime_frame_in).
func frame_at(inst: Vector4, time: float) -> Array:
	var held := inst.x < 0.0 # a stepped clip: its row alone
	var timed := inst.z < 0.0
	var first := -inst.x - 1.0 if held else inst.x
	var frames := absf(inst.y) # rows, or a timed clip's cells
	var fpos := time * absf(inst.z) + inst.w * frames
	var f0: float
	var f1: float
	if inst.y > 0.0:
		fpos = fposmod(fpos, frames)
		f0 = floorf(fpos)
		f1 = fmod(f0 + 1.0, frames) # a loop's last row blends into its first
	else:
		fpos = clampf(fpos, 0.0, frames if timed else frames - 1.0) # a timed one-shot ends at its last cell's end
		f0 = minf(floorf(fpos), frames - 1.0)
		f1 = minf(f0 + 1.0, frames - 1.0)
	var fr := fpos - f0
	if timed: # the cell's two rows from the map, the weight across the cell
		var m := _map_texel(int(first), int(frames), int(f0))
		f0 = m.x
		f1 = m.y
		fr = lerpf(m.z, m.w, fr)
	if held:
		return [int(first + f0), int(first + f0), 0.0]
	return [int(first + f0), int(first + f1), fr]

# A timed clip's map texel of `cell`: (r0, r1, f0, f1), rows relative to its first row, weights decoded; texel
# cell mod row_texels of row first - ceil(cells / row_texels) + cell / row_texels, addressed as any texel.
func _map_texel(first: int, cells: int, cell: int) -> Vector4:
	var m := _stored_texel(first - (cells + row_texels - 1) / row_texels + cell / row_texels, cell % row_texels)
	return Vector4(m.x, m.y, m.z / 65535.0, m.w / 65535.0) if precision == "u16" else m # u16 weights: round(f x 65535)

# ---- local rows (.pal version 6): [q (Vector4 x, y, z, w), p, s], v -> p + s R(q) (v - b_bone) ----

# A bone's local row blended between a frame's two rows (cb_local_blend of the GLSL).
func _local_blend(frame: Array, bone: int) -> Array:
	var q0 := _texel(frame[0], bone, 0)
	var q1 := _texel(frame[1], bone, 0)
	if q0.dot(q1) < 0.0:
		q1 = -q1 # the shorter way between the rows
	var ps := _texel(frame[0], bone, 1).lerp(_texel(frame[1], bone, 1), frame[2])
	return [q0.lerp(q1, frame[2]).normalized(), Vector3(ps.x, ps.y, ps.z), ps.w]

# A bone's local transform at this moment: its rows blended, cross-faded from from_frame's (fade < 1).
func _local_at(frame: Array, from_frame: Array, fade: float, bone: int) -> Array:
	var m := _local_blend(frame, bone)
	if fade >= 1.0:
		return m
	var f := _local_blend(from_frame, bone)
	var q: Vector4 = m[0]
	if f[0].dot(q) < 0.0:
		q = -q
	return [f[0].lerp(q, fade).normalized(), f[1].lerp(m[1], fade), lerpf(f[2], m[2], fade)]

# The composed skinning matrix of a bone of local rows: its local transform with each ancestor's put in front, up
# its chain (q = q_a q, s = s_a s, p = p_a + s_a rotate(q_a, p - b_a)), q normalised at the end.
func _composed(frame: Array, from_frame: Array, fade: float, bone: int) -> Transform3D:
	var m := _local_at(frame, from_frame, fade, bone)
	var q := Quaternion(m[0].x, m[0].y, m[0].z, m[0].w)
	var p: Vector3 = m[1]
	var s: float = m[2]
	var a := int(_bind[bone * 4 + 2 * bone_names.size() * 4])
	while a >= 0:
		var up := _local_at(frame, from_frame, fade, a)
		var qa := Quaternion(up[0].x, up[0].y, up[0].z, up[0].w)
		p = up[1] + up[2] * (qa * (p - _bind_position(a)))
		q = qa * q
		s *= up[2]
		a = int(_bind[a * 4 + 2 * bone_names.size() * 4])
	var basis := Basis(q.normalized()).scaled(Vector3.ONE * s)
	return Transform3D(basis, p - basis * _bind_position(bone))

func _bind_position(bone: int) -> Vector3:
	return Vector3(_bind[bone * 4], _bind[bone * 4 + 1], _bind[bone * 4 + 2])

# cb_bone as a matrix: the transform of points (w = 1), whose basis alone turns directions.
func _blend(row0: int, row1: int, fr: float, bone: int) -> Transform3D:
	var b := Vector3(_bind[bone * 4], _bind[bone * 4 + 1], _bind[bone * 4 + 2])
	var row := bone_names.size() * 4
	var o := Vector3(_bind[row + bone * 4], _bind[row + bone * 4 + 1], _bind[row + bone * 4 + 2])
	if layout == "qpos":
		var q0 := _texel(row0, bone, 0)
		var q1 := _texel(row1, bone, 0)
		if q0.dot(q1) < 0.0:
			q1 = -q1 # the shorter way between the rows
		var q := q0.lerp(q1, fr).normalized()
		var ps := _texel(row0, bone, 1).lerp(_texel(row1, bone, 1), fr)
		var basis := Basis(Quaternion(q.x, q.y, q.z, q.w)).scaled(Vector3.ONE * ps.w)
		return Transform3D(basis, Vector3(ps.x, ps.y, ps.z) + positions_relative * o - basis * b)
	var t: Array[Vector4] = []
	for k in _texels_per_bone:
		t.append(_texel(row0, bone, k).lerp(_texel(row1, bone, k), fr))
	var basis: Basis
	var p: Vector3
	if layout == "affine": # texel k is row k
		basis = Basis(Vector3(t[0].x, t[1].x, t[2].x), Vector3(t[0].y, t[1].y, t[2].y), Vector3(t[0].z, t[1].z, t[2].z))
		p = Vector3(t[0].w, t[1].w, t[2].w)
	else: # mat4: texel k is column k
		basis = Basis(Vector3(t[0].x, t[0].y, t[0].z), Vector3(t[1].x, t[1].y, t[1].z), Vector3(t[2].x, t[2].y, t[2].z))
		p = Vector3(t[3].x, t[3].y, t[3].z)
	# A half palette's translation holds the joint's position less the bone's offset: A (v - b) + p.
	return Transform3D(basis, p + positions_relative * (o - basis * b))

# Texel k (0 <= k < row_texels) of a row as stored: float and half as floats, u16 as its integers. Rows wrap
# into column blocks of rows_per_block rows.
func _stored_texel(row: int, k: int) -> Vector4:
	var block := row / rows_per_block
	var at := ((row - block * rows_per_block) * _width + block * row_texels + k) * _texel_bytes
	if precision == "float":
		return Vector4(_payload.decode_float(at), _payload.decode_float(at + 4), _payload.decode_float(at + 8), _payload.decode_float(at + 12))
	if precision == "half":
		return Vector4(_payload.decode_half(at), _payload.decode_half(at + 2), _payload.decode_half(at + 4), _payload.decode_half(at + 6))
	return Vector4(_payload.decode_u16(at), _payload.decode_u16(at + 2), _payload.decode_u16(at + 4), _payload.decode_u16(at + 6))

# Texel k of a bone in a baked row, decoded as the shader's cb_texel does.
func _texel(row: int, bone: int, k: int) -> Vector4:
	var u := _stored_texel(row, bone * _texels_per_bone + k)
	if precision != "u16":
		return u
	if local_rows and k == 1: # the bone's own ranges (bind_positions rows 3 and 4)
		var at_low := 3 * bone_names.size() * 4 + bone * 4 # bind_positions row 3, then row 4
		var at_high := at_low + bone_names.size() * 4
		var low := Vector4(_bind[at_low], _bind[at_low + 1], _bind[at_low + 2], 0.0)
		var high := Vector4(_bind[at_high], _bind[at_high + 1], _bind[at_high + 2], 0.0)
		var scale_max := _bind[at_low + 3]
		var box := low + (high - low) * (u / 65535.0)
		return Vector4(box.x, box.y, box.z, scale_max * u.w / 65535.0)
	return _decode_u16(u, k)

# cb_decode: crowdbake's u16 precision (docs/pal-format.md).
func _decode_u16(u: Vector4, k: int) -> Vector4:
	var snorm := Vector4(_snorm(u.x), _snorm(u.y), _snorm(u.z), _snorm(u.w))
	var box := bounds_min + (bounds_max - bounds_min) * (Vector3(u.x, u.y, u.z) / 65535.0)
	if layout == "qpos":
		return snorm if k == 0 else Vector4(box.x, box.y, box.z, linear_range * u.w / 65535.0)
	if layout == "affine":
		return Vector4(snorm.x * linear_range, snorm.y * linear_range, snorm.z * linear_range,
				bounds_min[k] + (bounds_max[k] - bounds_min[k]) * (u.w / 65535.0))
	if k == 3:
		return Vector4(box.x, box.y, box.z, 1.0)
	return Vector4(snorm.x * linear_range, snorm.y * linear_range, snorm.z * linear_range, 0.0)

static func _snorm(u: float) -> float:
	return maxf((u - 65536.0 if u >= 32768.0 else u) / 32767.0, -1.0)
