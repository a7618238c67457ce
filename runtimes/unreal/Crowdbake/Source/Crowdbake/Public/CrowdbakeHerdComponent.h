// CrowdbakeHerdComponent.h - a herd on an Instanced Static Mesh: every instance skinned in the
// material from a crowdbake palette (Crowdbake.ush through a Custom node), its clip, rate, phase
// and cross-fade as the instance's ten custom-data floats, written by the herd logic that
// tests/runtimes/test_unreal_reader.c checks outside Unreal (CrowdbakeHerdLogic). States come from a roster
// manifest's type, or one per clip of the palette.
//
//     Herd->SpawnHerd(500);
//     Herd->Place(7, FVector(400, 0, 0), 90.f, 1.2f);
//     Herd->SetState(7, TEXT("flee"), 0.3f);
//     Herd->SetSpeed(7, 9.9f);           // model units/s (metres for a glTF model): feet planted
//     FMatrix Head = Herd->BoneMatrixAt(7, 8);   // component space, for a prop
//     Herd->OnFootstep.AddDynamic(this, &AMyActor::Dust); // (Index, Bone, bLands, Time): the roster's contacts
//
// Each tick raises the footsteps the instances crossed and, for a palette with per-row travel
// (CBPAL_FLAG_ROW_TRAVEL), draws each moving instance at its place plus the travel offset, so its
// planted feet stay still while the game moves it at the state's speed.
#pragma once

#include "Components/InstancedStaticMeshComponent.h"
#include "CoreMinimal.h"
#include "CrowdbakeHerdLogic.h"
#include "Templates/UniquePtr.h"

#include "CrowdbakeHerdComponent.generated.h"

class UCrowdbakePalette;
class UMaterialInstanceDynamic;

DECLARE_DYNAMIC_MULTICAST_DELEGATE_FourParams(FCrowdbakeFootstep, int32, Index, int32, Bone, bool, bLands, float, Time);

UCLASS(ClassGroup = (Rendering), meta = (BlueprintSpawnableComponent))
class CROWDBAKE_API UCrowdbakeHerdComponent : public UInstancedStaticMeshComponent
{
    GENERATED_BODY()

public:
    UCrowdbakeHerdComponent();

    // The palette; the static mesh is `crowdbake mesh --vertex-id-uv 1` of the same model.
    UPROPERTY(EditAnywhere, BlueprintReadWrite, Category = "Crowdbake") TObjectPtr<UCrowdbakePalette> Palette;
    // A material whose Custom node includes /Plugin/Crowdbake/Private/Crowdbake.ush (runtimes/unreal/README.md),
    // with texture parameters Palette, BindPositions, Skin and vector parameters Header, BoundsMin, BoundsMax.
    UPROPERTY(EditAnywhere, BlueprintReadWrite, Category = "Crowdbake") TObjectPtr<UMaterialInterface> CrowdMaterial;
    // roster.json from `crowdbake bake CATALOG.toml` and the type to play (empty: one state per clip).
    UPROPERTY(EditAnywhere, BlueprintReadWrite, Category = "Crowdbake") FFilePath Roster;
    UPROPERTY(EditAnywhere, BlueprintReadWrite, Category = "Crowdbake") FString Type;
    UPROPERTY(EditAnywhere, BlueprintReadWrite, Category = "Crowdbake") float FadeSeconds = 0.25f;

    // Makes Count instances in the roster's default state (the first clip without a roster).
    UFUNCTION(BlueprintCallable, Category = "Crowdbake") void SpawnHerd(int32 Count);
    UFUNCTION(BlueprintCallable, Category = "Crowdbake") bool SetState(int32 Index, const FString &State, float Fade = -1.f);
    UFUNCTION(BlueprintCallable, Category = "Crowdbake") void SetSpeed(int32 Index, float Speed);
    UFUNCTION(BlueprintCallable, Category = "Crowdbake") void Place(int32 Index, FVector Location, float YawDegrees = 0.f, float Scale = 1.f);
    // The bone's skinning matrix for the instance now, in the component's space (Unreal units and axes).
    UFUNCTION(BlueprintCallable, Category = "Crowdbake") FMatrix BoneMatrixAt(int32 Index, int32 Bone) const;
    // A foot of an instance landed (bLands) or lifted: the roster's contacts, raised each tick in the
    // order crossed; Time is the world time of the crossing.
    UPROPERTY(BlueprintAssignable, Category = "Crowdbake") FCrowdbakeFootstep OnFootstep;

    virtual void TickComponent(float DeltaTime, ELevelTick TickType, FActorComponentTickFunction *ThisTickFunction) override;

private:
    void ApplyMaterial();
    void ApplyTravel();
    void LoadStates(std::vector<crowdbake::HerdStateInfo> &States, FString &DefaultState) const;
    void WriteCustomData(int32 Index);
    double Now() const;

    TUniquePtr<crowdbake::HerdLogic> Logic;
    TArray<FTransform> Placed; // each instance's place (Place), which the travel offset is added to
    TArray<FVector> DrawnOffset; // the offset each instance is drawn with now (glTF model units)
    bool bTravels = false;     // the palette carries per-row travel offsets
    UPROPERTY(Transient) TObjectPtr<UMaterialInstanceDynamic> Material;
};
