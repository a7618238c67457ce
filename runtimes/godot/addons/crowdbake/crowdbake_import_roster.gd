# crowdbake_import_roster.gd - the editor's importer for roster.json (registered by plugin.gd): the
# manifest of `crowdbake bake catalog.toml` is read and checked once, at import, by
# CrowdbakeRoster.import_file, and saved as a CrowdbakeRoster resource whose palettes are resolved:
# each .pal is referenced through its own import (crowdbake_import_palette.gd, which runs first). Then
# load("res://roster/roster.json") gives the roster in the editor and in exported games alike, a
# CrowdbakeHerd's `roster` property takes it in the inspector, and the export takes it and its
# palettes along: no "*.pal, *.json" non-resource filter.
#
# Godot picks an importer by the file's extension, so this one is offered every .json of the project:
# any other JSON is saved as the JSON resource Godot's own loader gives for it (load() works as before).
# A manifest the loader refuses, or a file that is not JSON, fails its import with one line.
@tool
extends EditorImportPlugin

const _Roster := preload("crowdbake_roster.gd")

func _get_importer_name() -> String:
	return "crowdbake.roster"

func _get_visible_name() -> String:
	return "crowdbake roster (other JSON as JSON)"

func _get_recognized_extensions() -> PackedStringArray:
	return PackedStringArray(["json"])

func _get_save_extension() -> String:
	return "res"

func _get_resource_type() -> String:
	return "Resource"

func _get_priority() -> float:
	return 1.0

# After the palettes (order 0), whose imports the roster references.
func _get_import_order() -> int:
	return 1

func _get_preset_count() -> int:
	return 1

func _get_preset_name(_preset: int) -> String:
	return "Default"

func _get_import_options(_path: String, _preset: int) -> Array[Dictionary]:
	return []

func _get_option_visibility(_path: String, _option: StringName, _options: Dictionary) -> bool:
	return true

func _import(source_file: String, save_path: String, _options: Dictionary, _platform_variants: Array[String],
		_gen_files: Array[String]) -> Error:
	var imported = _Roster.new().import_file(source_file)
	if imported is String:
		push_error(imported)
		return ERR_FILE_CORRUPT
	return ResourceSaver.save(imported, "%s.%s" % [save_path, _get_save_extension()])
