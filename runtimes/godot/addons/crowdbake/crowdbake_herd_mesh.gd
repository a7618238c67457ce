# crowdbake_herd_mesh.gd - the mesh a CrowdbakeHerd draws, with the model's look: each surface keeps
# its material's base colour, texture, vertex colours and alpha scissor, as parameters of its own copy
# of the herd's ShaderMaterial (the same skinning for every surface).
#
# Godot draws a MultiMesh once per surface of its mesh, so a 7-surface model would be 7 draw calls.
# Surfaces whose materials are plain colours (no texture, opaque: Quaternius' animals are all such)
# are merged into one surface, each one's colour moved into its vertices' colours: one draw call for
# them all. Textured or transparent surfaces stay surfaces of their own.
#
# The merged colours are the materials' sRGB albedo_color (8 bits a channel, as Godot stores vertex
# colours), which the shader linearises where the renderer lights in linear space and keeps where it
# lights in sRGB (the Compatibility renderer): what StandardMaterial3D does with its albedo. (Storing
# linear colours, as this file once did, drew the Compatibility renderer's herd 58% darker than Godot's
# own import of the same model: a linear 0.19 shown as is, where the material's sRGB 0.475 is.) A
# material that multiplies raw (linear) vertex colours in keeps a surface of its own, so that its
# colours meet the albedo exactly as in StandardMaterial3D.
extends RefCounted

# Returns { mesh, materials, merged (how many surfaces became one), surfaces (of the source) }.
static func build(source: Mesh, base: ShaderMaterial) -> Dictionary:
	var plain: Array[int] = []
	var own: Array[int] = []
	var influences := -1
	var surface := [] # the merged surfaces' metallic and roughness: the first plain one's
	for s in source.get_surface_count():
		var arrays := source.surface_get_arrays(s)
		var m: Material = source.surface_get_material(s)
		var per_vertex: int = arrays[Mesh.ARRAY_BONES].size() / maxi(1, arrays[Mesh.ARRAY_VERTEX].size())
		var mergeable: bool = _is_plain(m) and source.surface_get_primitive_type(s) == Mesh.PRIMITIVE_TRIANGLES \
				and (influences < 0 or (per_vertex == influences and _finish(m) == surface))
		if mergeable:
			influences = per_vertex
			surface = _finish(m)
			plain.append(s)
		else:
			own.append(s)
	var mesh := ArrayMesh.new()
	var materials: Array[ShaderMaterial] = []
	var flags: int = Mesh.ARRAY_FLAG_USE_8_BONE_WEIGHTS if influences == 8 else 0
	if not plain.is_empty():
		var merged := _merged(source, plain)
		_largest_first(merged, influences)
		mesh.add_surface_from_arrays(Mesh.PRIMITIVE_TRIANGLES, merged, [], {}, flags)
		materials.append(_look(base, source.surface_get_material(plain[0]), true))
	for s in own:
		var arrays := source.surface_get_arrays(s)
		var m: Material = source.surface_get_material(s)
		if not (m is BaseMaterial3D and m.vertex_color_use_as_albedo):
			arrays[Mesh.ARRAY_COLOR] = null # COLOR is the instance's tint alone
		var per_vertex: int = arrays[Mesh.ARRAY_BONES].size() / maxi(1, arrays[Mesh.ARRAY_VERTEX].size())
		_largest_first(arrays, per_vertex)
		mesh.add_surface_from_arrays(source.surface_get_primitive_type(s), arrays, [], {},
				Mesh.ARRAY_FLAG_USE_8_BONE_WEIGHTS if per_vertex == 8 else 0)
		materials.append(_look(base, m, false))
	for k in materials.size():
		mesh.surface_set_material(k, materials[k])
	return {"mesh": mesh, "materials": materials, "merged": plain.size(), "surfaces": source.get_surface_count()}

# Each vertex's influences ordered by weight, largest first (ties keep their order), as the animation
# LOD expects: the shader keeps a far instance's first one or two (crowdbake_herd.gdshader).
static func _largest_first(arrays: Array, per_vertex: int) -> void:
	var bones: PackedInt32Array = arrays[Mesh.ARRAY_BONES]
	var weights: PackedFloat32Array = arrays[Mesh.ARRAY_WEIGHTS]
	for base in range(0, weights.size(), per_vertex):
		for i in range(base + 1, base + per_vertex): # insertion sort: 4 or 8 influences
			var w := weights[i]
			var b := bones[i]
			var j := i
			while j > base and weights[j - 1] < w:
				weights[j] = weights[j - 1]
				bones[j] = bones[j - 1]
				j -= 1
			weights[j] = w
			bones[j] = b
	arrays[Mesh.ARRAY_BONES] = bones
	arrays[Mesh.ARRAY_WEIGHTS] = weights

# A plain colour: no material, or a BaseMaterial3D without an albedo texture, drawn opaque, whose
# vertex colours (if it uses them) are sRGB like its albedo.
static func _is_plain(m: Material) -> bool:
	if m == null:
		return true
	return m is BaseMaterial3D and m.albedo_texture == null and m.transparency == BaseMaterial3D.TRANSPARENCY_DISABLED \
			and (not m.vertex_color_use_as_albedo or m.vertex_color_is_srgb)

# What the merged surfaces must share: metallic and roughness.
static func _finish(m: Material) -> Array:
	return [m.metallic, m.roughness] if m is BaseMaterial3D else [0.0, 1.0]

# The surface's base colour, sRGB (as BaseMaterial3D.albedo_color is), for vertex colours.
static func _srgb_albedo(m: Material) -> Color:
	return m.albedo_color if m is BaseMaterial3D else Color.WHITE

# The surfaces `which` of `source` as one: positions, normals, tangents, UVs, bones and weights
# concatenated, indices offset, and each vertex's colour its surface's (times its own where the
# material uses vertex colours).
static func _merged(source: Mesh, which: Array[int]) -> Array:
	var out := []
	out.resize(Mesh.ARRAY_MAX)
	var vertices := PackedVector3Array()
	var normals := PackedVector3Array()
	var tangents := PackedFloat32Array()
	var uvs := PackedVector2Array()
	var colors := PackedColorArray()
	var bones := PackedInt32Array()
	var weights := PackedFloat32Array()
	var indices := PackedInt32Array()
	var all_normals := true
	var all_tangents := true
	for s in which:
		var a := source.surface_get_arrays(s)
		var m: Material = source.surface_get_material(s)
		var n: int = a[Mesh.ARRAY_VERTEX].size()
		var base := vertices.size()
		vertices.append_array(a[Mesh.ARRAY_VERTEX])
		all_normals = all_normals and a[Mesh.ARRAY_NORMAL] != null
		all_tangents = all_tangents and a[Mesh.ARRAY_TANGENT] != null
		if all_normals:
			normals.append_array(a[Mesh.ARRAY_NORMAL])
		if all_tangents:
			tangents.append_array(a[Mesh.ARRAY_TANGENT])
		var uv = a[Mesh.ARRAY_TEX_UV]
		for v in n:
			uvs.append(uv[v] if uv != null else Vector2.ZERO)
		var albedo := _srgb_albedo(m)
		var own_colors = a[Mesh.ARRAY_COLOR] if m is BaseMaterial3D and m.vertex_color_use_as_albedo else null
		for v in n:
			colors.append(albedo * own_colors[v] if own_colors != null else albedo)
		bones.append_array(a[Mesh.ARRAY_BONES])
		weights.append_array(a[Mesh.ARRAY_WEIGHTS])
		var index = a[Mesh.ARRAY_INDEX]
		if index == null:
			for v in n:
				indices.append(base + v)
		else:
			for i in index:
				indices.append(base + i)
	out[Mesh.ARRAY_VERTEX] = vertices
	out[Mesh.ARRAY_NORMAL] = normals if all_normals else null
	out[Mesh.ARRAY_TANGENT] = tangents if all_tangents and all_normals else null
	out[Mesh.ARRAY_TEX_UV] = uvs
	out[Mesh.ARRAY_COLOR] = colors
	out[Mesh.ARRAY_BONES] = bones
	out[Mesh.ARRAY_WEIGHTS] = weights
	out[Mesh.ARRAY_INDEX] = indices
	return out

# A copy of the herd's material set to one surface's look (merged: the plain surfaces, whose colours
# are in their vertices, and whose metallic and roughness are m's).
static func _look(base: ShaderMaterial, m: Material, merged: bool) -> ShaderMaterial:
	var look: ShaderMaterial = base.duplicate()
	if m is BaseMaterial3D:
		look.set_shader_parameter("metallic", m.metallic)
		look.set_shader_parameter("roughness", m.roughness)
	# COLOR holds sRGB: the merged colours, the instance colour alone, or vertex colours said to be sRGB.
	var own_colors: bool = not merged and m is BaseMaterial3D and m.vertex_color_use_as_albedo
	look.set_shader_parameter("color_is_srgb", m.vertex_color_is_srgb if own_colors else true)
	if m is BaseMaterial3D and not merged:
		look.set_shader_parameter("albedo", m.albedo_color)
		look.set_shader_parameter("albedo_texture", m.albedo_texture)
		look.set_shader_parameter("use_texture", m.albedo_texture != null)
		if m.transparency == BaseMaterial3D.TRANSPARENCY_ALPHA_SCISSOR:
			look.set_shader_parameter("alpha_scissor", m.alpha_scissor_threshold)
	return look
