// CrowdbakePaletteFactory.cpp - see CrowdbakePaletteFactory.h.
#include "CrowdbakePaletteFactory.h"

#include "CrowdbakePalette.h"
#include "EditorFramework/AssetImportData.h"
#include "Misc/FeedbackContext.h"
#include "Misc/FileHelper.h"
#include "Misc/Paths.h"

UCrowdbakePaletteFactory::UCrowdbakePaletteFactory()
{
    SupportedClass = UCrowdbakePalette::StaticClass();
    Formats.Add(TEXT("pal;crowdbake bone-matrix palette"));
    bCreateNew = false;
    bEditorImport = true;
}

UObject *UCrowdbakePaletteFactory::FactoryCreateBinary(UClass *InClass, UObject *InParent, FName InName, EObjectFlags Flags,
                                                       UObject *Context, const TCHAR *Type, const uint8 *&Buffer,
                                                       const uint8 *BufferEnd, FFeedbackContext *Warn)
{
    const FString File = GetCurrentFilename();
    TArray<uint8> Bytes(Buffer, (int32)(BufferEnd - Buffer));
    UCrowdbakePalette *Palette = NewObject<UCrowdbakePalette>(InParent, InClass, InName, Flags);
    FString Error;
    if (!Palette->ImportPal(Bytes, FPaths::GetCleanFilename(File), Error)) {
        Warn->Logf(ELogVerbosity::Error, TEXT("%s"), *Error);
        return nullptr;
    }
    // The mesh's skin texture (crowdbake mesh --skin-texture NAME.cbskin), when it lies beside the palette.
    const FString SkinFile = FPaths::ChangeExtension(File, TEXT("cbskin"));
    TArray<uint8> Skin;
    if (FPaths::FileExists(SkinFile) && FFileHelper::LoadFileToArray(Skin, *SkinFile) &&
        !Palette->ImportSkin(Skin, FPaths::GetCleanFilename(SkinFile), Error))
        Warn->Logf(ELogVerbosity::Warning, TEXT("%s (the palette imported without it)"), *Error);
    return Palette;
}
