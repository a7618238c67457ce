// CrowdbakePalette.cpp - see CrowdbakePalette.h. The reading is CrowdbakePalReader's (plain C++,
// tested outside Unreal); this file only moves its results into Unreal's types.
#include "CrowdbakePalette.h"

#include "Engine/Texture2D.h"
#include "CrowdbakePalReader.h"

namespace
{
// A transient texture holding Bytes as they are: nearest texels, no mips, no sRGB, no compression.
UTexture2D *RawTexture(UObject *Outer, int32 Width, int32 Height, EPixelFormat Format, const void *Bytes, int64 Size)
{
    UTexture2D *Texture = UTexture2D::CreateTransient(Width, Height, Format);
    if (!Texture) return nullptr;
    Texture->Filter = TF_Nearest;
    Texture->SRGB = false;
    Texture->AddressX = Texture->AddressY = TA_Clamp;
    FTexture2DMipMap &Mip = Texture->GetPlatformData()->Mips[0];
    void *Data = Mip.BulkData.Lock(LOCK_READ_WRITE);
    FMemory::Memcpy(Data, Bytes, Size);
    Mip.BulkData.Unlock();
    Texture->UpdateResource();
    return Texture;
}
} // namespace

bool UCrowdbakePalette::ImportPal(const TArray<uint8> &Bytes, const FString &Name, FString &Error)
{
    crowdbake::PalContents Pal;
    std::string Err;
    if (!crowdbake::ReadPal(Bytes.GetData(), (size_t)Bytes.Num(), TCHAR_TO_UTF8(*Name), Pal, Err)) {
        Error = UTF8_TO_TCHAR(Err.c_str());
        return false;
    }
    PalBytes = Bytes;
    Layout = (int32)Pal.layout, Precision = (int32)Pal.precision, Bones = (int32)Pal.bone_count;
    RowTexels = (int32)Pal.row_texels, RowsPerBlock = (int32)Pal.height, LinearRange = Pal.linear_range;
    BoundsMin = FVector3f(Pal.bounds_min[0], Pal.bounds_min[1], Pal.bounds_min[2]);
    BoundsMax = FVector3f(Pal.bounds_max[0], Pal.bounds_max[1], Pal.bounds_max[2]);
    AnimatedBounds = FBox3f(ForceInit);
    ClipNames.Reset();
    for (const crowdbake::PalClipInfo &Clip : Pal.clips) {
        ClipNames.Add(UTF8_TO_TCHAR(Clip.name.c_str()));
        AnimatedBounds += FBox3f(FVector3f(Clip.bounds_min[0], Clip.bounds_min[1], Clip.bounds_min[2]),
                                 FVector3f(Clip.bounds_max[0], Clip.bounds_max[1], Clip.bounds_max[2]));
    }
    ShaderDefines.Reset();
    for (const std::string &Define : Pal.defines) ShaderDefines.Add(UTF8_TO_TCHAR(Define.c_str()));
    BuildTextures();
    return true;
}

bool UCrowdbakePalette::ImportSkin(const TArray<uint8> &Bytes, const FString &Name, FString &Error)
{
    crowdbake::SkinContents Skin;
    std::string Err;
    if (!crowdbake::ReadSkin(Bytes.GetData(), (size_t)Bytes.Num(), TCHAR_TO_UTF8(*Name), Skin, Err)) {
        Error = UTF8_TO_TCHAR(Err.c_str());
        return false;
    }
    SkinBytes = Bytes;
    BuildTextures();
    return true;
}

void UCrowdbakePalette::PostLoad()
{
    Super::PostLoad();
    BuildTextures();
}

void UCrowdbakePalette::BuildTextures()
{
    crowdbake::PalContents Pal;
    std::string Err;
    if (PalBytes.Num() && crowdbake::ReadPal(PalBytes.GetData(), (size_t)PalBytes.Num(), "palette", Pal, Err)) {
        const EPixelFormat Formats[] = {PF_A32B32G32R32F, PF_FloatRGBA, PF_R16G16B16A16_UNORM};
        PaletteTexture = RawTexture(this, (int32)Pal.width, (int32)Pal.height, Formats[Pal.precision], Pal.texels.data(),
                                    (int64)Pal.texels.size());
        BindPositionsTexture = RawTexture(this, (int32)Pal.bone_count, (int32)Pal.bind_rows, PF_A32B32G32R32F, Pal.bind_texels.data(),
                                          (int64)Pal.bind_texels.size() * 4);
    }
    crowdbake::SkinContents Skin;
    if (SkinBytes.Num() && crowdbake::ReadSkin(SkinBytes.GetData(), (size_t)SkinBytes.Num(), "skin", Skin, Err))
        SkinTexture = RawTexture(this, (int32)Skin.width, (int32)Skin.height, PF_A32B32G32R32F, Skin.texels.data(),
                                 (int64)Skin.texels.size() * 4);
}

FMatrix44f UCrowdbakePalette::InstanceBoneMatrix(const float CustomData[4], double Time, int32 Bone) const
{
    float M[16];
    FMatrix44f Out = FMatrix44f::Identity;
    if (Bone < 0 || !crowdbake::InstanceBoneMatrix(PalBytes.GetData(), (size_t)PalBytes.Num(), CustomData, Time, (uint32_t)Bone, M))
        return Out;
    for (int K = 0; K < 16; ++K) Out.M[K / 4][K % 4] = M[K]; // column k of the glTF matrix is Unreal's row k
    return Out;
}
