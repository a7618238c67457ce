// CrowdbakeHerdComponent.cpp - see CrowdbakeHerdComponent.h. The palette is in glTF space (metres,
// +Y up); Crowdbake.ush converts with CROWDBAKE_GLTF_FROM_UNREAL (x, z, y) / 100 by default, and
// BoneMatrixAt does the same here.
#include "CrowdbakeHerdComponent.h"

#include "CrowdbakePalette.h"
#include "Dom/JsonObject.h"
#include "Engine/StaticMesh.h"
#include "Engine/World.h"
#include "Materials/MaterialInstanceDynamic.h"
#include "Misc/FileHelper.h"
#include "Serialization/JsonReader.h"
#include "Serialization/JsonSerializer.h"

namespace
{
// glTF (x, y, z) in metres -> Unreal (100 x, 100 z, 100 y): the default of Crowdbake.ush.
const FMatrix GltfToUnreal(FPlane(100, 0, 0, 0), FPlane(0, 0, 100, 0), FPlane(0, 100, 0, 0), FPlane(0, 0, 0, 1));
} // namespace

UCrowdbakeHerdComponent::UCrowdbakeHerdComponent()
{
    NumCustomDataFloats = crowdbake::HerdLogic::kCustomDataFloats;
    PrimaryComponentTick.bCanEverTick = true; // footsteps and travel offsets
}

double UCrowdbakeHerdComponent::Now() const
{
    const UWorld *World = GetWorld();
    return World ? World->GetTimeSeconds() : 0.0; // the material's Time node: the world's game time
}

namespace
{
// The state's clip's fps (a timed clip's cells / duration) and contacts, from the type's `clips` (docs/roster.md).
void LoadContacts(const TArray<TSharedPtr<FJsonValue>> *Clips, const FString &ClipName, crowdbake::HerdStateInfo &Info)
{
    if (!Clips) return;
    for (const TSharedPtr<FJsonValue> &Value : *Clips) {
        const TSharedPtr<FJsonObject> Clip = Value->AsObject();
        if (!Clip.IsValid() || Clip->GetStringField(TEXT("name")) != ClipName) continue;
        Info.clip_fps = (float)Clip->GetNumberField(TEXT("fps"));
        const TSharedPtr<FJsonObject> *Timed;
        if (Clip->TryGetObjectField(TEXT("timed_rows"), Timed))
            Info.clip_fps = (float)((*Timed)->GetNumberField(TEXT("cells")) / Clip->GetNumberField(TEXT("duration")));
        const TArray<TSharedPtr<FJsonValue>> *Contacts;
        if (!Clip->TryGetArrayField(TEXT("contacts"), Contacts)) return;
        for (const TSharedPtr<FJsonValue> &C : *Contacts) {
            const TSharedPtr<FJsonObject> K = C->AsObject();
            if (!K.IsValid()) continue;
            crowdbake::HerdContact Contact;
            Contact.foot = TCHAR_TO_UTF8(*K->GetStringField(TEXT("foot")));
            Contact.bone = (int32_t)K->GetNumberField(TEXT("bone"));
            Contact.time = (float)K->GetNumberField(TEXT("time"));
            Contact.lift = (float)K->GetNumberField(TEXT("lift"));
            Info.contacts.push_back(Contact);
        }
        return;
    }
}

// The clip's rows and its timed_rows (docs/roster.md; none: cells 0), from the type's `clips`.
crowdbake::HerdClipRows ClipRows(const TArray<TSharedPtr<FJsonValue>> *Clips, const FString &ClipName)
{
    crowdbake::HerdClipRows Rows;
    Rows.name = TCHAR_TO_UTF8(*ClipName);
    if (!Clips) return Rows;
    for (const TSharedPtr<FJsonValue> &Value : *Clips) {
        const TSharedPtr<FJsonObject> Clip = Value->AsObject();
        if (!Clip.IsValid() || Clip->GetStringField(TEXT("name")) != ClipName) continue;
        Rows.first_row = (int32_t)Clip->GetNumberField(TEXT("first_row"));
        Rows.frame_count = (int32_t)Clip->GetNumberField(TEXT("frame_count"));
        const TSharedPtr<FJsonObject> *Timed;
        if (Clip->TryGetObjectField(TEXT("timed_rows"), Timed)) { // .pal version 7: its states count cells at negative rates
            Rows.cells = (int32_t)(*Timed)->GetNumberField(TEXT("cells"));
            Rows.cell_rate = (float)(*Timed)->GetNumberField(TEXT("cell_rate"));
            Rows.map_rows = (int32_t)(*Timed)->GetNumberField(TEXT("map_rows"));
        }
        break;
    }
    return Rows;
}
} // namespace

void UCrowdbakeHerdComponent::LoadStates(std::vector<crowdbake::HerdStateInfo> &States, FString &DefaultState) const
{
    FString Text;
    TSharedPtr<FJsonObject> Doc;
    if (Roster.FilePath.IsEmpty() || !FFileHelper::LoadFileToString(Text, *Roster.FilePath) ||
        !FJsonSerializer::Deserialize(TJsonReaderFactory<>::Create(Text), Doc) || !Doc.IsValid())
        return;
    const TSharedPtr<FJsonObject> *Types, *TypeObject, *StateMap;
    if (!Doc->TryGetObjectField(TEXT("types"), Types) || !(*Types)->TryGetObjectField(Type, TypeObject) ||
        !(*TypeObject)->TryGetObjectField(TEXT("states"), StateMap))
        return;
    (*TypeObject)->TryGetStringField(TEXT("default_state"), DefaultState);
    const TArray<TSharedPtr<FJsonValue>> *Clips = nullptr;
    (*TypeObject)->TryGetArrayField(TEXT("clips"), Clips);
    for (const auto &Entry : (*StateMap)->Values) {
        const TSharedPtr<FJsonObject> State = Entry.Value->AsObject();
        const TSharedPtr<FJsonObject> *Inst;
        if (!State.IsValid() || !State->TryGetObjectField(TEXT("instance"), Inst)) continue;
        crowdbake::HerdStateInfo Info;
        Info.name = TCHAR_TO_UTF8(*Entry.Key);
        Info.first_row = (int32_t)(*Inst)->GetNumberField(TEXT("first_row"));
        Info.frame_count = (int32_t)(*Inst)->GetNumberField(TEXT("frame_count"));
        Info.rate = (float)(*Inst)->GetNumberField(TEXT("rate"));
        Info.rate_per_speed = (float)(*Inst)->GetNumberField(TEXT("rate_per_speed"));
        Info.golden_ratio_phase = (*Inst)->GetStringField(TEXT("phase")) == TEXT("golden_ratio");
        LoadContacts(Clips, State->GetStringField(TEXT("clip")), Info);
        // A state that does not fit its clip (a timed clip's cells and negative rates) is refused as readRoster refuses it.
        std::string Error;
        if (!crowdbake::CheckRosterState(Info, ClipRows(Clips, State->GetStringField(TEXT("clip"))),
                                         (int32_t)(*TypeObject)->GetNumberField(TEXT("rows")),
                                         "types." + std::string(TCHAR_TO_UTF8(*Type)) + ".states." + Info.name + ".instance", Error)) {
            UE_LOG(LogTemp, Error, TEXT("CrowdbakeHerd %s: %s: %s"), *GetName(), *Roster.FilePath, UTF8_TO_TCHAR(Error.c_str()));
            States.clear();
            return;
        }
        States.push_back(Info);
    }
}

void UCrowdbakeHerdComponent::SpawnHerd(int32 Count)
{
    if (!Palette) return;
    std::vector<crowdbake::HerdStateInfo> States;
    FString DefaultState;
    LoadStates(States, DefaultState);
    crowdbake::PalContents Pal;
    std::string Error;
    if (!crowdbake::ReadPal(Palette->PalBytes.GetData(), (size_t)Palette->PalBytes.Num(), "palette", Pal, Error)) return;
    if (States.empty()) States = crowdbake::StatesFromClips(Pal);
    bTravels = Pal.row_travel;
    Logic = MakeUnique<crowdbake::HerdLogic>(States, Count, FadeSeconds);
    ClearInstances();
    SetNumCustomDataFloats(crowdbake::HerdLogic::kCustomDataFloats);
    Placed.Init(FTransform::Identity, Count);
    DrawnOffset.Init(FVector::ZeroVector, Count);
    for (int32 I = 0; I < Count; ++I) AddInstance(FTransform::Identity);
    for (int32 I = 0; I < Count; ++I) {
        if (!DefaultState.IsEmpty()) Logic->SetState(I, TCHAR_TO_UTF8(*DefaultState), Now(), 0.f);
        WriteCustomData(I);
    }
    // Culling: the instances' bounds must hold every baked pose, which reaches past the rest pose.
    const FBox3f Anim = Palette->AnimatedBounds;
    const FVector Size = GltfToUnreal.TransformVector(FVector(Anim.GetSize())).GetAbs();
    const FVector Rest = GetStaticMesh() ? GetStaticMesh()->GetBounds().BoxExtent * 2.0 : Size;
    BoundsScale = FMath::Max(1.f, (float)(Size.GetMax() / FMath::Max(Rest.GetMin(), 1.0)));
    ApplyMaterial();
}

void UCrowdbakeHerdComponent::ApplyMaterial()
{
    if (!CrowdMaterial || !Palette) return;
    Material = UMaterialInstanceDynamic::Create(CrowdMaterial, this);
    Material->SetTextureParameterValue(TEXT("Palette"), Palette->PaletteTexture);
    Material->SetTextureParameterValue(TEXT("BindPositions"), Palette->BindPositionsTexture);
    Material->SetTextureParameterValue(TEXT("Skin"), Palette->SkinTexture);
    Material->SetVectorParameterValue(TEXT("Header"), FLinearColor((float)Palette->RowTexels, (float)Palette->RowsPerBlock, Palette->LinearRange, 0.f));
    Material->SetVectorParameterValue(TEXT("BoundsMin"), FLinearColor(Palette->BoundsMin.X, Palette->BoundsMin.Y, Palette->BoundsMin.Z, 0.f));
    Material->SetVectorParameterValue(TEXT("BoundsMax"), FLinearColor(Palette->BoundsMax.X, Palette->BoundsMax.Y, Palette->BoundsMax.Z, 0.f));
    SetMaterial(0, Material);
}

void UCrowdbakeHerdComponent::WriteCustomData(int32 Index)
{
    const float *Data = Logic->CustomData(Index);
    SetCustomData(Index, TArray<float>(Data, crowdbake::HerdLogic::kCustomDataFloats), true);
}

bool UCrowdbakeHerdComponent::SetState(int32 Index, const FString &State, float Fade)
{
    if (!Logic || !Logic->SetState(Index, TCHAR_TO_UTF8(*State), Now(), Fade)) {
        UE_LOG(LogTemp, Warning, TEXT("CrowdbakeHerd %s: no state '%s' (have %s)"), *GetName(), *State,
               Logic ? UTF8_TO_TCHAR(Logic->StateNames().c_str()) : TEXT("none: SpawnHerd first"));
        return false;
    }
    WriteCustomData(Index);
    return true;
}

void UCrowdbakeHerdComponent::SetSpeed(int32 Index, float Speed)
{
    if (!Logic) return;
    Logic->SetSpeed(Index, Speed, Now());
    WriteCustomData(Index);
}

void UCrowdbakeHerdComponent::Place(int32 Index, FVector Location, float YawDegrees, float Scale)
{
    if (!Placed.IsValidIndex(Index)) return;
    Placed[Index] = FTransform(FRotator(0, YawDegrees, 0), Location, FVector(Scale));
    DrawnOffset[Index] = FVector::ZeroVector; // drawn at the place itself until the next tick adds the offset
    UpdateInstanceTransform(Index, Placed[Index], false, true);
    if (!Logic) return;
    Logic->SetScale(Index, Scale, Now());
    WriteCustomData(Index);
}

void UCrowdbakeHerdComponent::TickComponent(float DeltaTime, ELevelTick TickType, FActorComponentTickFunction *ThisTickFunction)
{
    Super::TickComponent(DeltaTime, TickType, ThisTickFunction);
    if (!Logic) return;
    if (OnFootstep.IsBound()) {
        std::vector<crowdbake::Footstep> Steps;
        Logic->Advance(Now(), Steps);
        for (const crowdbake::Footstep &S : Steps) OnFootstep.Broadcast(S.instance, S.bone, S.lands, (float)S.time);
    }
    if (bTravels) ApplyTravel();
}

// Each instance drawn at its place plus its travel offset (glTF model units, rotated and scaled as
// the instance is: GltfToUnreal, then the place's transform). Only instances whose offset changed
// are moved (a standing or non-locomotion instance keeps offset 0 and costs no transform update).
void UCrowdbakeHerdComponent::ApplyTravel()
{
    const double T = Now();
    bool Moved = false;
    for (int32 I = 0; I < Placed.Num(); ++I) {
        float O[3];
        Logic->TravelOffsetAt(Palette->PalBytes.GetData(), (size_t)Palette->PalBytes.Num(), I, T, O);
        const FVector Offset(O[0], O[1], O[2]);
        if (Offset == DrawnOffset[I]) continue;
        DrawnOffset[I] = Offset;
        FTransform Drawn = Placed[I];
        Drawn.AddToTranslation(Placed[I].TransformVector(GltfToUnreal.TransformVector(Offset)));
        UpdateInstanceTransform(I, Drawn, false, false, true);
        Moved = true;
    }
    if (Moved) MarkRenderStateDirty();
}

FMatrix UCrowdbakeHerdComponent::BoneMatrixAt(int32 Index, int32 Bone) const
{
    float M[16];
    if (!Logic || !Palette || Bone < 0 ||
        !Logic->BoneMatrixAt(Palette->PalBytes.GetData(), (size_t)Palette->PalBytes.Num(), Index, (uint32_t)Bone, Now(), M))
        return FMatrix::Identity;
    FMatrix Gltf;
    for (int K = 0; K < 16; ++K) Gltf.M[K / 4][K % 4] = M[K]; // Unreal's row k is the glTF matrix's column k
    FTransform Instance;
    GetInstanceTransform(Index, Instance, false);
    return GltfToUnreal.Inverse() * Gltf * GltfToUnreal * Instance.ToMatrixWithScale();
}
