// CrowdbakeRosterAsset.cs - an imported roster manifest (docs/roster.md): each type's clip table,
// states, sockets and footstep contacts, and its palette asset. CrowdbakeRosterImporter makes it
// from a roster.json (or a manifest baked with --manifest NAME.roster).
using System.Collections.Generic;
using UnityEngine;

namespace Crowdbake
{
    public sealed class CrowdbakeRosterAsset : ScriptableObject
    {
        [SerializeField, HideInInspector] string json;
        public string[] typeNames;
        public CrowdbakePaletteAsset[] palettes; // by type, in typeNames' order (null: its palette is not in the project)

        Roster roster;

        public Roster Roster
        {
            get {
                if (roster == null) roster = Roster.Parse(json, name);
                return roster;
            }
        }

        // Reads the manifest's text (throws JsonException naming the file and the field).
        public static CrowdbakeRosterAsset FromJson(string text, string assetName)
        {
            Roster parsed = Roster.Parse(text, assetName);
            var asset = CreateInstance<CrowdbakeRosterAsset>();
            asset.name = assetName;
            asset.json = text;
            asset.roster = parsed;
            var names = new List<string>();
            foreach (RosterType t in parsed.types) names.Add(t.name);
            asset.typeNames = names.ToArray();
            asset.palettes = new CrowdbakePaletteAsset[names.Count];
            return asset;
        }

        public RosterType Type(string typeName) { return Roster.Type(typeName); }

        public CrowdbakePaletteAsset PaletteOf(string typeName)
        {
            int i = System.Array.IndexOf(typeNames, typeName);
            return i >= 0 ? palettes[i] : null;
        }
    }
}
