# crowdbake_demo.gd - a herd in a field: bake a catalog (`crowdbake bake catalog.toml`), copy its
# roster/ folder and the animal's .glb into the project, set the three exports, and run the scene.
# Instances walk at different sizes and speeds; click to send every animal into the next state.
extends Node3D

@export_file("*.json") var roster_path := "res://roster/roster.json"
@export var animal := "cow"
@export var model: PackedScene # the animal's glTF, imported (its skinned mesh is the herd's mesh)
@export var animals := 64

@onready var herd: CrowdbakeHerd = $Herd

func _ready() -> void:
	var roster = ResourceLoader.load(roster_path, "CrowdbakeRoster")
	if roster == null or model == null:
		push_error("crowdbake demo: set roster_path (a roster.json) and model (the animal's .glb) on %s" % name)
		return
	herd.setup(roster, animal, CrowdbakeHerd.skinned_mesh_in(model.instantiate()), animals)
	var side := ceili(sqrt(animals))
	for i in animals:
		var size := 0.8 + 0.4 * fmod(i * 0.37, 1.0)
		herd.place(i, Transform3D(Basis(Vector3.UP, i * 2.4).scaled(Vector3.ONE * size), Vector3(i % side - side / 2.0, 0, i / side - side / 2.0) * 3.0))
		herd.set_speed(i, 0.8 + 0.6 * fmod(i * 0.61, 1.0))
		herd.set_color(i, Color.from_hsv(fmod(i * 0.13, 1.0), 0.3, 1.0))

func _unhandled_input(event: InputEvent) -> void:
	if event is InputEventMouseButton and event.pressed and herd.palette != null:
		var states: Array = herd.roster.types[animal]["states"].keys()
		for i in animals:
			herd.set_state(i, states[(states.find(herd.get_state(i)) + 1) % states.size()])
