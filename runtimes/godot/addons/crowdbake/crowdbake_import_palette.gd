# crowdbake_import_palette.gd - the editor's importer for .pal files (registered by plugin.gd): each
# palette is read and checked once, at import, by CrowdbakePalette.load_file, and saved as a
# resource in .godot/imported. load("res://roster/cow.pal") then gives the CrowdbakePalette in the
# editor and in exported games alike, and the export takes it with the other resources: no "*.pal"
# non-resource filter. A palette the loader refuses fails its import with the loader's one line
# (the preset, the save and the refusal: crowdbake_import_base.gd).
@tool
extends "crowdbake_import_base.gd"

const _Palette := preload("crowdbake_palette.gd")

func _get_importer_name() -> String:
	return "crowdbake.palette"

func _get_visible_name() -> String:
	return "crowdbake palette"

func _get_recognized_extensions() -> PackedStringArray:
	return PackedStringArray(["pal"])

func _get_import_order() -> int:
	return 0

func _read(source_file: String) -> Variant:
	var palette := _Palette.new()
	if not palette.load_file(source_file):
		return palette.error
	return palette
