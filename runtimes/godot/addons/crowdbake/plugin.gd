# plugin.gd - the editor side of the crowdbake addon. Its classes (CrowdbakeHerd in the Create Node
# dialog, CrowdbakePalette, CrowdbakeRoster) and its ResourceFormatLoader (crowdbake_format_loader.gd)
# are registered by their class_name, in the editor and in exported games alike, so the plugin has
# nothing to add; enabling it marks the addon as in use.
@tool
extends EditorPlugin
