# crowdbake_roster.gd - a roster manifest (roster.json of `crowdbake bake catalog.toml`) as a Godot
# resource: each animal type's palette (a CrowdbakePalette), states, clips and sockets.
#
#   var roster: CrowdbakeRoster = ResourceLoader.load("res://roster/roster.json", "CrowdbakeRoster")
#   var cow: Dictionary = roster.types["cow"]   # palette, states, clips, sockets, default_state
#
# Godot's own JSON loader answers a plain load() of a .json; the type hint picks this one. In the editor
# the plugin's roster import (crowdbake_import_roster.gd) saves the roster, its palettes resolved, as a
# resource: then load("res://roster/roster.json") gives it, and exports take it and its palettes along.
@tool
class_name CrowdbakeRoster
extends Resource

const _Palette := preload("crowdbake_palette.gd")
const SCHEMA := "crowdbake-roster/1"

# Type name -> {palette, states (the manifest's), clips (the manifest's, by name: contacts among
# them when the bake wrote them), sockets (name -> {bone, transform}), default_state, speed_reference}.
@export_storage var types := {}
var error := "" # the last failure, one line

func load_file(path: String) -> bool:
	var text := FileAccess.get_file_as_string(path)
	if text.is_empty():
		return _fail("%s: cannot read the roster manifest (%s)" % [path, error_string(FileAccess.get_open_error())])
	var parsed = JSON.parse_string(text)
	if not (parsed is Dictionary and parsed.get("schema") == SCHEMA and parsed.get("types") is Dictionary):
		return _fail("%s is not a crowdbake roster (schema %s); give the roster.json that `crowdbake bake catalog.toml` wrote"
				% [path, SCHEMA])
	for name in parsed["types"]:
		var entry: Dictionary = parsed["types"][name]
		var palette_path := path.get_base_dir().path_join(str(entry.get("palette", "")))
		var palette = _palette(palette_path)
		if palette is String:
			return _fail(palette)
		var clips := {}
		for clip in entry.get("clips", []):
			clips[clip["name"]] = clip
		for state in entry.get("states", {}):
			var wrong := _state_error("types.%s.states.%s.instance" % [name, state], entry["states"][state], clips, int(entry.get("rows", -1)))
			if not wrong.is_empty():
				return _fail("%s: %s" % [path, wrong])
		types[name] = {"palette": palette, "states": entry.get("states", {}), "clips": clips,
				"sockets": _sockets(entry.get("sockets", {})), "default_state": entry.get("default_state", ""),
				"speed_reference": float(entry.get("speed_reference", palette.speed_reference)),
				"animation_lod": entry.get("animation_lod", {})}
	return true

# Why a state does not fit its clip and the type's `rows`, as readRoster (crowdbake_pal.mjs) checks it: a timed clip's
# (its `timed_rows`, .pal version 7) states count its cells and play at negative rates (rate and rate_per_speed),
# every other clip's at rates >= 0 (`rows` < 0: not known). "" when it fits; else one line naming the field under `at`.
static func _state_error(at: String, state: Dictionary, clips: Dictionary, rows: int) -> String:
	var inst: Dictionary = state.get("instance", {})
	var clip_name := str(state.get("clip", ""))
	var clip: Dictionary = clips.get(clip_name, {})
	var timed_rows: Dictionary = clip.get("timed_rows", {})
	var timed := not timed_rows.is_empty()
	var rate := float(inst.get("rate", 0.0))
	var per_speed := float(inst.get("rate_per_speed", 0.0))
	var frames := int(inst.get("frame_count", 0))
	if (rate < 0.0) != timed or per_speed * rate < 0.0:
		return "%s.rate: %s" % [at, ("clip \"%s\" has timed rows: rate and rate_per_speed must be negative" % clip_name) if timed
				else "expected a number >= 0, and rate_per_speed too"]
	if frames == 0:
		return "%s.frame_count: expected a non-zero integer" % at
	if timed and absi(frames) != int(timed_rows.get("cells", 0)):
		return "%s.frame_count: clip \"%s\" has %d cells, got %d" % [at, clip_name, int(timed_rows.get("cells", 0)), frames]
	var first_row := int(inst.get("first_row", 0))
	var first := -first_row - 1 if first_row < 0 else first_row # held rows: -first_row - 1
	var count := int(clip.get("frame_count", 0)) if timed else absi(frames) # a timed state counts cells, not rows
	if (rows >= 0 and first + count > rows) or (timed and int(timed_rows.get("map_rows", 0)) > first):
		return "%s: rows %d..%d outside the type's %d rows" % [at, first, first + count, rows]
	return ""

# What the editor's import of the .json at `path` saves (crowdbake_import_roster.gd): a roster manifest
# as this CrowdbakeRoster, its palettes resolved (in a project each is its own import, referenced; else read
# from the file and kept inside); any other JSON as the JSON resource Godot's own loader gives for it,
# so that the project's other .json files load() as before. A String (one line) when it cannot be had.
func import_file(path: String):
	var text := FileAccess.get_file_as_string(path)
	var json := JSON.new()
	if json.parse(text) != OK:
		return "%s:%d: %s; fix the JSON" % [path, json.get_error_line(), json.get_error_message()]
	var data = json.data
	if not (data is Dictionary and str(data.get("schema", "")).begins_with("crowdbake-roster/")):
		return json
	return self if load_file(path) else error

# The palette at `path`: in a project (res://), through load(), which gives the imported resource
# (crowdbake_import_palette.gd; what an exported game has); elsewhere read from the file. The error
# line when it cannot be had.
static func _palette(path: String):
	if path.begins_with("res://") and ResourceLoader.exists(path):
		var imported = load(path)
		return imported if imported != null else "%s: Godot could not load it (see its import errors)" % path
	var palette := _Palette.new()
	return palette if palette.load_file(path) else palette.error

# Sockets, as the manifest lists them ([{name, bone, bind_transform}]) or a map of name -> {bone,
# bind_transform}; the transform (the socket's frame in bind space, 16 numbers column-major like the
# joint matrices: the prop's place is instance x bone matrix x this) defaults to the identity.
static func _sockets(listed) -> Dictionary:
	var out := {}
	var entries: Array = listed.values() if listed is Dictionary else listed
	var names: Array = listed.keys() if listed is Dictionary else []
	for i in entries.size():
		var e: Dictionary = entries[i]
		var m: Array = e.get("bind_transform", e.get("transform", []))
		var t := Transform3D()
		if m.size() == 16:
			t = Transform3D(Vector3(m[0], m[1], m[2]), Vector3(m[4], m[5], m[6]), Vector3(m[8], m[9], m[10]), Vector3(m[12], m[13], m[14]))
		out[names[i] if names else e.get("name", "")] = {"bone": int(e.get("bone", 0)), "transform": t}
	return out

func _fail(message: String) -> bool:
	error = message
	push_error(message)
	return false
