// CrowdbakePalImporter.cs - imports a .pal palette as a CrowdbakePaletteAsset with its two textures
// as sub-assets. A damaged or compressed file fails the import with the reader's one-line message
// (file, place, fix) in the Console.
using System.IO;
using UnityEditor.AssetImporters;
using UnityEngine;

namespace Crowdbake.Editor
{
    [ScriptedImporter(1, "pal")]
    public sealed class CrowdbakePalImporter : ScriptedImporter
    {
        public override void OnImportAsset(AssetImportContext ctx)
        {
            string assetName = Path.GetFileNameWithoutExtension(ctx.assetPath);
            CrowdbakePaletteAsset asset;
            try {
                asset = CrowdbakePaletteAsset.FromBytes(File.ReadAllBytes(ctx.assetPath), assetName);
            } catch (PalException e) {
                ctx.LogImportError(ctx.assetPath + ": " + e.Message);
                return;
            }
            ctx.AddObjectToAsset("palette", asset);
            ctx.AddObjectToAsset("palette texture", asset.palette);
            ctx.AddObjectToAsset("bind positions", asset.bindPositions);
            ctx.SetMainObject(asset);
        }
    }
}
