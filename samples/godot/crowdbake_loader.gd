# crowdbake_loader.gd - loads crowdbake palettes and the roster manifest into Godot 4.
#
#   var loader := CrowdbakeLoader.new()
#   loader.load_roster("res://roster/roster.json")
#   loader.fill_herd($Goats, "goat", "wander", 1.4, 200, 30.0)   # a MultiMeshInstance3D
#
# The .pal format is docs/pal-format.md; only half and float palettes map onto Godot images.
class_name CrowdbakeLoader
extends RefCounted

const GOLDEN := 0.6180339887
const LAYOUTS := ["mat4", "affine", "qpos"]

var roster: Dictionary = {}
var _dir := ""

func load_roster(path: String) -> void:
	roster = JSON.parse_string(FileAccess.get_file_as_string(path))
	assert(roster != null and roster.get("schema") == "crowdbake-roster/1", "%s is not a crowdbake roster" % path)
	_dir = path.get_base_dir()

# Reads a .pal and returns {texture, bind_positions, layout, row_texels, rows_per_block}.
func load_palette(path: String) -> Dictionary:
	var f := FileAccess.open(path, FileAccess.READ)
	assert(f != null, "cannot open %s" % path)
	var head := f.get_buffer(256)
	assert(head.slice(0, 5).get_string_from_ascii() == "CBPAL", "%s is not a crowdbake palette" % path)
	assert(head.decode_u32(8) == 1, "%s: palette format version %d is not supported" % [path, head.decode_u32(8)])
	var flags := head.decode_u32(12)
	var layout := head.decode_u32(20)
	var precision := head.decode_u32(24)
	assert(flags & 1 == 0, "%s is zstd-compressed: bake without --zstd for Godot" % path)
	assert(precision != 2, "%s is u16: Godot images have no RGBA16UI format; bake with --precision half" % path)
	var bones := head.decode_u32(32)
	var width := head.decode_u32(44)
	var height := head.decode_u32(48)
	var bone_table := head.decode_u64(128)
	var payload_offset := head.decode_u64(152)
	var payload_size := head.decode_u64(160)
	f.seek(payload_offset)
	var format := Image.FORMAT_RGBAF if precision == 0 else Image.FORMAT_RGBAH
	var image := Image.create_from_data(width, height, false, format, f.get_buffer(payload_size))
	var bind := PackedFloat32Array()
	f.seek(bone_table)
	for i in bones:
		var entry := f.get_buffer(32)
		bind.append_array([entry.decode_float(16), entry.decode_float(20), entry.decode_float(24), 0.0])
	var bind_image := Image.create_from_data(bones, 1, false, Image.FORMAT_RGBAF, bind.to_byte_array())
	return {
		"texture": ImageTexture.create_from_image(image),
		"bind_positions": ImageTexture.create_from_image(bind_image),
		"layout": LAYOUTS[layout],
		"row_texels": head.decode_u32(36),
		"rows_per_block": height,
	}

# Points a MultiMeshInstance3D (its mesh skinned, material = crowdbake_crowd.gdshader) at a type's
# palette and fills `count` instances in `state` at ground speed `speed`, spread over a square.
func fill_herd(node: MultiMeshInstance3D, type: String, state: String, speed: float, count: int, spread: float) -> void:
	var t: Dictionary = roster["types"][type]
	var pal := load_palette(_dir.path_join(t["palette"]))
	var material := node.material_override as ShaderMaterial
	assert(material != null, "give %s a ShaderMaterial with crowdbake_crowd.gdshader" % node.name)
	material.set_shader_parameter("palette", pal["texture"])
	material.set_shader_parameter("bind_positions", pal["bind_positions"])
	material.set_shader_parameter("row_texels", pal["row_texels"])
	material.set_shader_parameter("rows_per_block", pal["rows_per_block"])
	var inst: Dictionary = t["states"][state]["instance"]
	var rate: float = inst["rate"] if inst["rate_per_speed"] == 0.0 else inst["rate_per_speed"] * speed
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
