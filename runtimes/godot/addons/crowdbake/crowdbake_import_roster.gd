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
# A manifest the loader refuses, or a file that is not JSON, fails its import with one line (the
# preset, the save and the refusal: crowdbake_import_base.gd).
@tool
extends "crowdbake_import_base.gd"

const _Roster := preload("crowdbake_roster.gd")

func _get_importer_name() -> String:
	return "crowdbake.roster"

func _get_visible_name() -> String:
	return "crowdbake roster (other JSON as JSON)"

func _get_recognized_extensions() -> PackedStringArray:
	return PackedStringArray(["json"])

# After the palettes (order 0), whose imports the roster references.
func _get_import_order() -> int:
	return 1

func _read(source_file: String) -> Variant:
	return _Roster.new().import_file(source_file)
