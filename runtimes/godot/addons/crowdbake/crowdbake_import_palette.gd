# crowdbake_import_palette.gd - the editor's importer for .pal files (registered by plugin.gd): each
# palette is read and checked once, at import, by CrowdbakePalette.load_file, and saved as a
# resource in .godot/imported. load("res://roster/cow.pal") then gives the CrowdbakePalette in the
# editor and in exported games alike, and the export takes it with the other resources: no "*.pal"
# non-resource filter. A palette the loader refuses fails its import with the loader's one line.
@tool
extends EditorImportPlugin

const _Palette := preload("crowdbake_palette.gd")

func _get_importer_name() -> String:
	return "crowdbake.palette"

func _get_visible_name() -> String:
	return "crowdbake palette"

func _get_recognized_extensions() -> PackedStringArray:
	return PackedStringArray(["pal"])

func _get_save_extension() -> String:
	return "res"

func _get_resource_type() -> String:
	return "Resource"

func _get_priority() -> float:
	return 1.0

func _get_import_order() -> int:
	return 0

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
	var palette := _Palette.new()
	if not palette.load_file(source_file):
		push_error(palette.error)
		return ERR_FILE_CORRUPT
	return ResourceSaver.save(palette, "%s.%s" % [save_path, _get_save_extension()])
