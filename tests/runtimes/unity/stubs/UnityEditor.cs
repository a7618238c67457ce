// UnityEditor.cs - stubs of exactly the UnityEditor API the Crowdbake package's importers call, as
// the Unity Scripting Reference documents it (see UnityEngine.cs).
using System;

namespace UnityEditor
{
    public static class AssetDatabase
    {
        public static T LoadAssetAtPath<T>(string assetPath) where T : UnityEngine.Object { return null; }
    }
}

namespace UnityEditor.AssetImporters
{
    public abstract class AssetImporter : UnityEngine.Object { }

    public abstract class ScriptedImporter : AssetImporter
    {
        public abstract void OnImportAsset(AssetImportContext ctx);
    }

    [AttributeUsage(AttributeTargets.Class, Inherited = false)]
    public sealed class ScriptedImporterAttribute : Attribute
    {
        public ScriptedImporterAttribute(int version, string ext) { }
        public ScriptedImporterAttribute(int version, string[] exts, string[] overrideExts) { }
    }

    public sealed class AssetImportContext
    {
        public string assetPath { get { return null; } }
        public void AddObjectToAsset(string identifier, UnityEngine.Object obj) { }
        public void SetMainObject(UnityEngine.Object obj) { }
        public void LogImportError(string msg, UnityEngine.Object obj = null) { }
        public void DependsOnSourceAsset(string path) { }
    }
}
