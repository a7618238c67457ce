// CrowdbakeRosterImporter.cs - imports a roster manifest as a CrowdbakeRosterAsset: types, clip
// tables, states, sockets and contacts, each type linked to its .pal's imported asset. It claims
// files named *.roster (bake with `--manifest Assets/Crowd/herd.roster`); for a roster.json, pick it
// in the file's Inspector (Importer: Crowdbake roster), since it cannot claim every .json file.
using System.IO;
using UnityEditor;
using UnityEditor.AssetImporters;
using UnityEngine;

namespace Crowdbake.Editor
{
    [ScriptedImporter(1, new[] { "roster" }, new[] { "json" })]
    public sealed class CrowdbakeRosterImporter : ScriptedImporter
    {
        public override void OnImportAsset(AssetImportContext ctx)
        {
            string assetName = Path.GetFileNameWithoutExtension(ctx.assetPath);
            CrowdbakeRosterAsset asset;
            try {
                asset = CrowdbakeRosterAsset.FromJson(File.ReadAllText(ctx.assetPath), assetName);
            } catch (JsonException e) {
                ctx.LogImportError(e.Message);
                return;
            }
            string dir = Path.GetDirectoryName(ctx.assetPath);
            for (int i = 0; i < asset.typeNames.Length; ++i) {
                RosterType t = asset.Type(asset.typeNames[i]);
                if (t.palette == null) continue; // an EXR-only type: no .pal to link
                string palPath = Path.Combine(dir, t.palette).Replace('\\', '/');
                ctx.DependsOnSourceAsset(palPath); // re-imported when the palette is
                asset.palettes[i] = AssetDatabase.LoadAssetAtPath<CrowdbakePaletteAsset>(palPath);
            }
            ctx.AddObjectToAsset("roster", asset);
            ctx.SetMainObject(asset);
        }
    }
}
