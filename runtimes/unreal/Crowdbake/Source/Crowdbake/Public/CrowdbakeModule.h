// CrowdbakeModule.h - the runtime module: maps the plugin's Shaders folder to /Plugin/Crowdbake so a
// material's Custom node can include /Plugin/Crowdbake/Private/Crowdbake.ush.
#pragma once

#include "Modules/ModuleInterface.h"

class FCrowdbakeModule : public IModuleInterface
{
public:
    virtual void StartupModule() override;
    virtual void ShutdownModule() override;
};
