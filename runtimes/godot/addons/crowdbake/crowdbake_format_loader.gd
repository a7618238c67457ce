# crowdbake_format_loader.gd - lets load() read crowdbake files as ready resources:
#   load("res://roster/goat.pal")                        -> CrowdbakePalette
#   ResourceLoader.load("res://roster/roster.json", "CrowdbakeRoster")  -> CrowdbakeRoster
# Godot registers a ResourceFormatLoader that has a class_name by itself (editor and exported game);
# where scripts carry no global class names, register one by hand:
#   ResourceLoader.add_resource_format_loader(preload("crowdbake_format_loader.gd").new())
# With the plugin enabled, the editor imports .pal and roster.json files (crowdbake_import_palette.gd,
# crowdbake_import_roster.gd), so load() answers from their imports and exports take them along; this
# loader is for files outside the project (user://, a mod folder) and projects without the plugin,
# whose exports need "*.pal, *.json" in the preset's non-resource files filter.
@tool
class_name CrowdbakeFormatLoader
extends ResourceFormatLoader

const _Palette := preload("crowdbake_palette.gd")
const _Roster := preload("crowdbake_roster.gd")
const ROSTER_TYPE := "CrowdbakeRoster"

func _get_recognized_extensions() -> PackedStringArray:
	return PackedStringArray(["pal", "json"])

# A .json is a roster only when asked for one (the type hint): Godot's JSON loader keeps the rest.
func _recognize_path(path: String, type: StringName) -> bool:
	var ext := path.get_extension().to_lower()
	return ext == "pal" or (ext == "json" and type == ROSTER_TYPE)

func _handles_type(type: StringName) -> bool:
	return type in [&"Resource", &"CrowdbakePalette", &"CrowdbakeRoster"]

func _get_resource_type(path: String) -> String:
	return "Resource" if path.get_extension().to_lower() == "pal" else ""

func _load(path: String, _original_path: String, _use_sub_threads: bool, _cache_mode: int) -> Variant:
	var resource = _Palette.new() if path.get_extension().to_lower() == "pal" else _Roster.new()
	if not resource.load_file(path):
		return ERR_FILE_CORRUPT
	return resource
