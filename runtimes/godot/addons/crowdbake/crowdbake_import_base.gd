# crowdbake_import_base.gd - what the editor's two importers (crowdbake_import_palette.gd for .pal,
# crowdbake_import_roster.gd for roster.json) share: one preset with no options, a resource saved in
# .godot/imported as .res, and a file the loader refuses failing its import with the loader's one
# line. An importer extends this and says its name, its extensions and its order, and reads a file
# in _read: the resource to save, or the loader's error as a String.
@tool
extends EditorImportPlugin

func _read(_source_file: String) -> Variant:
	return "crowdbake_import_base.gd: an importer must override _read"

func _get_save_extension() -> String:
	return "res"

func _get_resource_type() -> String:
	return "Resource"

func _get_priority() -> float:
	return 1.0

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
	var imported = _read(source_file)
	if imported is String:
		push_error(imported)
		return ERR_FILE_CORRUPT
	return ResourceSaver.save(imported, "%s.%s" % [save_path, _get_save_extension()])
