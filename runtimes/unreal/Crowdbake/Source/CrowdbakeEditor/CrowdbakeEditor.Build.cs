// CrowdbakeEditor.Build.cs - the editor module: the .pal import factory.
using UnrealBuildTool;

public class CrowdbakeEditor : ModuleRules
{
    public CrowdbakeEditor(ReadOnlyTargetRules Target) : base(Target)
    {
        PCHUsage = PCHUsageMode.UseExplicitOrSharedPCHs;
        PrivateDependencyModuleNames.AddRange(new string[] { "Core", "CoreUObject", "Engine", "UnrealEd", "Crowdbake" });
    }
}
