// CrowdbakePaletteAsset.cs - an imported .pal: the palette texture and the bind-position texture
// the shader reads, the numbers of its header the shader needs, and the file itself (the clip table,
// and the rows BoneMatrixAt decodes on the CPU for sockets). CrowdbakePalImporter makes it.
using UnityEngine;

namespace Crowdbake
{
    public sealed class CrowdbakePaletteAsset : ScriptableObject
    {
        public Texture2D palette;       // RGBA32F, RGBA16F or RGBA64 (u16 as UNORM16: the shader's CB_U16_UNORM)
        public Texture2D bindPositions; // RGBA32F, bones x 2: bind positions, then position offsets; local rows:
                                        // bones x 5, rows 2-4 the parents and each bone's ranges
        public int layout, precision, rowTexels, rowsPerBlock;
        public bool positionsRelative;
        public bool localRows;               // .pal version 6 flag bit 5: the shader's CB_LOCAL_ROWS composes each bone
        public Vector3 boundsMin, boundsMax; // u16: the box positions are quantized in
        public float linearRange;
        public Bounds animatedBounds;        // every clip's skinned mesh at every baked row, model space
        public string[] clipNames;
        [SerializeField, HideInInspector] byte[] file; // the .pal as it was imported

        PalFile pal;

        // The reader over the imported bytes (made once, on first use).
        public PalFile Pal
        {
            get {
                if (pal == null) pal = PalFile.Read(file, name, false);
                return pal;
            }
        }

        // The shader keywords of this palette's encoding (the HLSL runtime's defines).
        public string[] Keywords
        {
            get {
                string[] layouts = { "CB_LAYOUT_MAT4", "CB_LAYOUT_AFFINE", "CB_LAYOUT_QPOS" };
                string[] precisions = { "CB_PRECISION_FLOAT", "CB_PRECISION_HALF", "CB_PRECISION_U16" };
                var keywords = new System.Collections.Generic.List<string> { layouts[layout], precisions[precision] };
                if (positionsRelative) keywords.Add("CB_POSITIONS_RELATIVE");
                if (localRows) keywords.Add("CB_LOCAL_ROWS");
                return keywords.ToArray();
            }
        }

        // Reads a .pal file's bytes into a new asset (throws PalException with a one-line message).
        public static CrowdbakePaletteAsset FromBytes(byte[] bytes, string assetName)
        {
            PalFile pal = PalFile.Read(bytes, assetName, true);
            PalHeader h = pal.Header;
            var asset = CreateInstance<CrowdbakePaletteAsset>();
            asset.name = assetName;
            asset.file = bytes;
            asset.pal = pal;
            asset.layout = (int)h.Layout;
            asset.precision = (int)h.Precision;
            asset.rowTexels = (int)h.RowTexels;
            asset.rowsPerBlock = (int)h.Height;
            asset.positionsRelative = (h.Flags & PalFile.FlagPositionsRelative) != 0;
            asset.localRows = pal.LocalRows;
            asset.boundsMin = new Vector3(h.BoundsMin[0], h.BoundsMin[1], h.BoundsMin[2]);
            asset.boundsMax = new Vector3(h.BoundsMax[0], h.BoundsMax[1], h.BoundsMax[2]);
            asset.linearRange = h.LinearRange;
            asset.clipNames = new string[pal.Clips.Length];
            for (int i = 0; i < pal.Clips.Length; ++i) {
                PalClip c = pal.Clips[i];
                asset.clipNames[i] = c.Name;
                var box = new Bounds();
                box.SetMinMax(new Vector3(c.BoundsMin[0], c.BoundsMin[1], c.BoundsMin[2]),
                              new Vector3(c.BoundsMax[0], c.BoundsMax[1], c.BoundsMax[2]));
                if (i == 0) asset.animatedBounds = box;
                else asset.animatedBounds.Encapsulate(box);
            }
            asset.palette = PaletteTexture(pal, assetName);
            asset.bindPositions = BindTexture(pal, assetName);
            return asset;
        }

        // The payload as it is in the file: no conversion, nearest texels, no mips, linear.
        static Texture2D PaletteTexture(PalFile pal, string assetName)
        {
            TextureFormat[] formats = { TextureFormat.RGBAFloat, TextureFormat.RGBAHalf, TextureFormat.RGBA64 };
            var t = new Texture2D((int)pal.Header.Width, (int)pal.Header.Height, formats[pal.Header.Precision], false, true);
            t.name = assetName + " palette";
            t.filterMode = FilterMode.Point;
            t.wrapMode = TextureWrapMode.Clamp;
            t.SetPixelData(pal.Data, 0, pal.TexelOffset);
            t.Apply(false, true);
            return t;
        }

        // One texel per bone: row 0 the bind positions, row 1 the position offsets; for local rows also
        // row 2 the parent (-1: a root), row 3 (pos_min, scale_max), row 4 (pos_max, 0) (PalFile.BindTexels).
        static Texture2D BindTexture(PalFile pal, string assetName)
        {
            float[] texels = pal.BindTexels();
            var t = new Texture2D(pal.Bones.Length, texels.Length / (pal.Bones.Length * 4), TextureFormat.RGBAFloat, false, true);
            t.name = assetName + " bind positions";
            t.filterMode = FilterMode.Point;
            t.wrapMode = TextureWrapMode.Clamp;
            t.SetPixelData(texels, 0);
            t.Apply(false, true);
            return t;
        }

        // Binds the textures and numbers to a draw's property block.
        public void SetProperties(MaterialPropertyBlock block)
        {
            block.SetTexture("cb_palette", palette);
            block.SetTexture("cb_bind_positions", bindPositions);
            block.SetFloat("cb_row_texels", rowTexels);
            block.SetFloat("cb_rows_per_block", rowsPerBlock);
            block.SetVector("cb_bounds_min", boundsMin);
            block.SetVector("cb_bounds_max", boundsMax);
            block.SetFloat("cb_linear_range", linearRange);
        }

        // The bone pass kernel's palette (CrowdbakeBonePass.compute): the textures and numbers SetProperties binds, and
        // this palette's keywords on, every other one of the encoding's off (the kernel asset is shared: set before
        // each dispatch, which takes the keywords as they are when it is issued).
        public void SetComputeProperties(ComputeShader cs, int kernel)
        {
            var on = new System.Collections.Generic.List<string>(Keywords);
            foreach (string k in AllKeywords)
                if (on.Contains(k)) cs.EnableKeyword(k);
                else cs.DisableKeyword(k);
            cs.SetTexture(kernel, "cb_palette", palette);
            cs.SetTexture(kernel, "cb_bind_positions", bindPositions);
            cs.SetFloat("cb_row_texels", rowTexels);
            cs.SetFloat("cb_rows_per_block", rowsPerBlock);
            cs.SetVector("cb_bounds_min", boundsMin);
            cs.SetVector("cb_bounds_max", boundsMax);
            cs.SetFloat("cb_linear_range", linearRange);
        }

        static readonly string[] AllKeywords = { "CB_LAYOUT_MAT4", "CB_LAYOUT_AFFINE", "CB_LAYOUT_QPOS", "CB_PRECISION_FLOAT",
                                                 "CB_PRECISION_HALF", "CB_PRECISION_U16", "CB_POSITIONS_RELATIVE", "CB_LOCAL_ROWS" };

        // A copy of `material` with this palette's keywords on (the shader's multi_compile sets).
        public Material MaterialFor(Material material)
        {
            var m = new Material(material);
            m.name = material.name + " (" + name + ")";
            foreach (string k in Keywords) m.EnableKeyword(k);
            m.enableInstancing = true;
            return m;
        }
    }
}
