# plugin.gd - the editor side of the crowdbake addon. Its classes (CrowdbakeHerd in the Create Node
# dialog, CrowdbakePalette, CrowdbakeRoster) and its ResourceFormatLoader (crowdbake_format_loader.gd)
# are registered by their class_name, in the editor and in exported games alike. The plugin adds the
# .pal importer (crowdbake_import_palette.gd) and the roster.json importer (crowdbake_import_roster.gd):
# palettes and rosters become resources the export takes along.
@tool
extends EditorPlugin

var _palette_importer: EditorImportPlugin
var _roster_importer: EditorImportPlugin

func _enter_tree() -> void:
	_palette_importer = preload("crowdbake_import_palette.gd").new()
	_roster_importer = preload("crowdbake_import_roster.gd").new()
	add_import_plugin(_palette_importer)
	add_import_plugin(_roster_importer)

func _exit_tree() -> void:
	remove_import_plugin(_palette_importer)
	remove_import_plugin(_roster_importer)
	_palette_importer = null
	_roster_importer = null
