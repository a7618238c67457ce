// CrowdbakeModule.cpp - see CrowdbakeModule.h. The mapping must exist before shaders compile: the
// module loads in PostConfigInit (Crowdbake.uplugin).
#include "CrowdbakeModule.h"

#include "Interfaces/IPluginManager.h"
#include "Misc/Paths.h"
#include "Modules/ModuleManager.h"
#include "ShaderCore.h"

void FCrowdbakeModule::StartupModule()
{
    const FString ShaderDir = FPaths::Combine(IPluginManager::Get().FindPlugin(TEXT("Crowdbake"))->GetBaseDir(), TEXT("Shaders"));
    AddShaderSourceDirectoryMapping(TEXT("/Plugin/Crowdbake"), ShaderDir);
}

void FCrowdbakeModule::ShutdownModule()
{
}

IMPLEMENT_MODULE(FCrowdbakeModule, Crowdbake)
