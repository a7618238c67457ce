// Crowdbake.Build.cs - the runtime module: the palette asset, the herd component, the shader
// directory mapping. The .pal reading goes through the project's C reader, crowdbake_pal.h, found
// in the crowdbake checkout's include/ (CROWDBAKE_INCLUDE overrides where it is).
using System;
using System.IO;
using UnrealBuildTool;

public class Crowdbake : ModuleRules
{
    public Crowdbake(ReadOnlyTargetRules Target) : base(Target)
    {
        PCHUsage = PCHUsageMode.UseExplicitOrSharedPCHs;
        PublicDependencyModuleNames.AddRange(new string[] { "Core", "CoreUObject", "Engine", "RenderCore", "RHI", "Json" });
        PrivateDependencyModuleNames.AddRange(new string[] { "Projects" });
        string reader = Environment.GetEnvironmentVariable("CROWDBAKE_INCLUDE");
        if (string.IsNullOrEmpty(reader)) reader = Path.GetFullPath(Path.Combine(ModuleDirectory, "..", "..", "..", "..", "..", "include"));
        PrivateIncludePaths.Add(reader);
    }
}
