# crowdbake_demo.gd - a herd in a field. It opens to the addon's own herd: the project's generated
# quadruped and its roster, which `make` bakes into demo/herd/ (demo/herd.toml). For your animal,
# bake a catalog (`crowdbake bake catalog.toml`), copy its roster/ folder and the animal's .glb into
# the project, and set roster_path, animal and model (or model_path). Instances walk at different
# sizes and speeds; click to send every animal into the next state.
extends Node3D

const _Herd := preload("../crowdbake_herd.gd")

@export_file("*.json") var roster_path := "res://addons/crowdbake/demo/herd/roster.json"
@export var animal := "goat"
@export var model: PackedScene # the animal's glTF as imported; when unset, model_path is read
@export_file("*.glb", "*.gltf") var model_path := "res://addons/crowdbake/demo/herd/quadruped.glb"
@export var animals := 64

@onready var herd = $Herd

func _ready() -> void:
	# The editor's import (a CrowdbakeRoster, with the plugin on), else the file read at run time.
	var roster = load(roster_path) if ResourceLoader.exists(roster_path) else null
	if roster == null or roster.get("types") == null:
		roster = ResourceLoader.load(roster_path, "CrowdbakeRoster", ResourceLoader.CACHE_MODE_IGNORE)
	var scene := _model_scene()
	if roster == null or scene == null:
		push_error("crowdbake demo: set roster_path (a roster.json) and model or model_path (the animal's glTF) on %s" % name)
		return
	herd.setup(roster, animal, _Herd.skinned_mesh_in(scene), animals)
	scene.free()
	var side := ceili(sqrt(animals))
	for i in animals:
		var size := 0.8 + 0.4 * fmod(i * 0.37, 1.0)
		herd.place(i, Transform3D(Basis(Vector3.UP, i * 2.4).scaled(Vector3.ONE * size), Vector3(i % side - side / 2.0, 0, i / side - side / 2.0) * 3.0))
		herd.set_speed(i, 0.8 + 0.6 * fmod(i * 0.61, 1.0))
		herd.set_color(i, Color.from_hsv(fmod(i * 0.13, 1.0), 0.15, 1.0))

# The animal's scene: `model`, the imported glTF at model_path, or the file read by GLTFDocument
# (a glTF outside the project's imports).
func _model_scene() -> Node:
	if model != null:
		return model.instantiate()
	if ResourceLoader.exists(model_path, "PackedScene"):
		return load(model_path).instantiate()
	var doc := GLTFDocument.new()
	var state := GLTFState.new()
	return doc.generate_scene(state) if doc.append_from_file(model_path, state) == OK else null

func _unhandled_input(event: InputEvent) -> void:
	if event is InputEventMouseButton and event.pressed and herd.palette != null:
		var states: Array = herd.roster.types[animal]["states"].keys()
		for i in animals:
			herd.set_state(i, states[(states.find(herd.get_state(i)) + 1) % states.size()])
