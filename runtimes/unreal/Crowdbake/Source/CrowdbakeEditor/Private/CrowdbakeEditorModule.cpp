// CrowdbakeEditorModule.cpp - the editor module: nothing to start; it carries the import factory.
#include "Modules/ModuleManager.h"

IMPLEMENT_MODULE(FDefaultModuleImpl, CrowdbakeEditor)
