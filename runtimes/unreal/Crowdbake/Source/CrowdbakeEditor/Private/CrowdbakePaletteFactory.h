// CrowdbakePaletteFactory.h - imports .pal files as UCrowdbakePalette assets (drag one into the
// Content Browser), and a .cbskin beside it (same name) as the asset's skin texture. The reading
// is CrowdbakePalReader's, through crowdbake_pal.h; a bad file fails the import with its one-line
// message.
#pragma once

#include "CoreMinimal.h"
#include "Factories/Factory.h"

#include "CrowdbakePaletteFactory.generated.h"

UCLASS()
class UCrowdbakePaletteFactory : public UFactory
{
    GENERATED_BODY()

public:
    UCrowdbakePaletteFactory();
    virtual UObject *FactoryCreateBinary(UClass *InClass, UObject *InParent, FName InName, EObjectFlags Flags, UObject *Context,
                                         const TCHAR *Type, const uint8 *&Buffer, const uint8 *BufferEnd, FFeedbackContext *Warn) override;
};
