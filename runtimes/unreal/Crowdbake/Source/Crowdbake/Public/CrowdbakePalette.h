// CrowdbakePalette.h - a crowdbake palette as an Unreal asset: the .pal file's bytes (imported by
// UCrowdbakePaletteFactory) and what its header says, with the textures the Crowdbake.ush material
// code reads made from it when it loads: the palette (PF_A32B32G32R32F, PF_FloatRGBA or
// PF_R16G16B16A16_UNORM: the texels exactly as the file holds them), the bind positions, and the
// skin (joints and weights by vertex id, from `crowdbake mesh --skin-texture`).
#pragma once

#include "CoreMinimal.h"
#include "UObject/Object.h"

#include "CrowdbakePalette.generated.h"

class UTexture2D;

UCLASS(BlueprintType)
class CROWDBAKE_API UCrowdbakePalette : public UObject
{
    GENERATED_BODY()

public:
    // Reads and checks a .pal file (through crowdbake_pal.h); false with a one-line Error.
    bool ImportPal(const TArray<uint8> &Bytes, const FString &Name, FString &Error);
    // Reads a .cbskin file written by `crowdbake mesh --skin-texture`; false with a one-line Error.
    bool ImportSkin(const TArray<uint8> &Bytes, const FString &Name, FString &Error);

    virtual void PostLoad() override;

    // The skinning matrix (glTF space, column-major as FMatrix44f rows = columns) of Bone for the
    // ten custom-data floats of an instance at Time; identity when the bone does not exist.
    FMatrix44f InstanceBoneMatrix(const float CustomData[4], double Time, int32 Bone) const;

    UPROPERTY(VisibleAnywhere, Category = "Crowdbake") int32 Layout = 0;    // 0 mat4, 1 affine, 2 qpos
    UPROPERTY(VisibleAnywhere, Category = "Crowdbake") int32 Precision = 0; // 0 float, 1 half, 2 u16
    UPROPERTY(VisibleAnywhere, Category = "Crowdbake") int32 Bones = 0;
    UPROPERTY(VisibleAnywhere, Category = "Crowdbake") int32 RowTexels = 0;
    UPROPERTY(VisibleAnywhere, Category = "Crowdbake") int32 RowsPerBlock = 0;
    UPROPERTY(VisibleAnywhere, Category = "Crowdbake") float LinearRange = 0;
    UPROPERTY(VisibleAnywhere, Category = "Crowdbake") FVector3f BoundsMin = FVector3f::ZeroVector;
    UPROPERTY(VisibleAnywhere, Category = "Crowdbake") FVector3f BoundsMax = FVector3f::ZeroVector;
    UPROPERTY(VisibleAnywhere, Category = "Crowdbake") FBox3f AnimatedBounds; // every clip's skinned mesh, glTF space
    UPROPERTY(VisibleAnywhere, Category = "Crowdbake") TArray<FString> ClipNames;
    // The Custom node's Additional Defines for this palette: CB_LAYOUT_QPOS=1 ...
    UPROPERTY(VisibleAnywhere, Category = "Crowdbake") TArray<FString> ShaderDefines;

    UPROPERTY(Transient, BlueprintReadOnly, Category = "Crowdbake") TObjectPtr<UTexture2D> PaletteTexture;
    UPROPERTY(Transient, BlueprintReadOnly, Category = "Crowdbake") TObjectPtr<UTexture2D> BindPositionsTexture;
    UPROPERTY(Transient, BlueprintReadOnly, Category = "Crowdbake") TObjectPtr<UTexture2D> SkinTexture;

    UPROPERTY() TArray<uint8> PalBytes;
    UPROPERTY() TArray<uint8> SkinBytes;

private:
    void BuildTextures();
};
