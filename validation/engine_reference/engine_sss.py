#!/usr/bin/env python3
"""Transcription of the engines' own subsurface-profile code: asset fields -> rendered profile.

Pure Python (no numpy needed). Every engine function below is a literal transcription of the
engine source named in its comment (repository, path, commit, function), with the key lines
quoted. Nothing here is derived from baker/src/export; the only non-engine code is
(a) the inverse direction (Burley (A, d) -> fields), obtained by inverting the transcribed
forward chain and then checked by running the forward chain again, and (b) the block marked
"NOT ENGINE CODE: exporter claim" used only for comparison in pinned.json.

Run `python3 engine_sss.py` to (re)write pinned.json next to this file.

Sources (retrieved from the stored public-repository index; see README.md):

Unreal Engine 5.4 (izzy2lost/UnrealEngineUWP, a public mirror; Engine/Build/Build.version = 5.4.0):
  UE54_CPP  = izzy2lost/UnrealEngineUWP @ 7b4334123ac75039401fdc7d3f1a3afc068fe74f
              Engine/Source/Runtime/Engine/Private/Rendering/SubsurfaceProfile.cpp
  UE54_H    = izzy2lost/UnrealEngineUWP @ 7b4334123ac75039401fdc7d3f1a3afc068fe74f
              Engine/Source/Runtime/Engine/Classes/Engine/SubsurfaceProfile.h
  UE54_USH  = izzy2lost/UnrealEngineUWP @ 09ef6f1c14e7639be7c4b24c73a5f8bcd487bb9c
              Engine/Shaders/Private/SubsurfaceBurleyNormalized.ush
  UE54_USF  = izzy2lost/UnrealEngineUWP @ 09ef6f1c14e7639be7c4b24c73a5f8bcd487bb9c
              Engine/Shaders/Private/PostProcessSubsurface.usf
  UE5_COMMON= chenyong2github/UnrealEngine @ 078f5165f17d3962a1f160954e864f5fc1a5776d
              Engine/Shaders/Private/BurleyNormalizedSSSCommon.ush
  UE5x_BNSSS= Engine/Source/Runtime/Engine/Private/Rendering/BurleyNormalizedSSS.cpp, the
              UE 5.1-5.7 form (has r.SSProfiles.Transmission.UseLegacy); stored in the index as
              file id 738507513 whose repository the index does not name (see README).
Unreal Engine 5.8 (unicorn2022/UE5.8.0 @ 5d9a05c15b1f8c6d7b3354b360677ce30d688149; Build.version 5.8.0):
  UE58_MATH = Engine/Source/Runtime/Engine/Classes/Engine/SubsurfaceScatteringMath.h
  UE58_CPP  = Engine/Source/Runtime/Engine/Private/Rendering/SubsurfaceProfile.cpp

Unity HDRP (Unity-Technologies/Graphics):
  HDRP_CS   = @ 0777f7c62a9e8dadacf5e95b784bcb4ee44d6539
              Packages/com.unity.render-pipelines.high-definition/Runtime/Material/DiffusionProfile/DiffusionProfileSettings.cs
  HDRP_HLSL = @ 0ae669bca675075dc6cacb81438585438547ad78
              com.unity.render-pipelines.high-definition/Runtime/Material/DiffusionProfile/DiffusionProfile.hlsl
  HDRP_SSS  = @ 0ad4df76eca680f501de667cb56ef1ef113bef86
              Packages/com.unity.render-pipelines.high-definition/Runtime/Material/SubsurfaceScattering/SubsurfaceScattering.compute
  HDRP_UTIL = @ 094ba766dbcc2911f870c2618cc19570b25f6419
              Packages/com.unity.render-pipelines.high-definition/Runtime/RenderPipeline/Utility/HDUtils.cs
"""

from __future__ import annotations

import json
import math
import os
import struct

RGB = range(3)


def f32(x: float) -> float:
    """Round to IEEE float32 (the engines compute in float; used only for the 16-bit encode)."""
    return struct.unpack("f", struct.pack("f", x))[0]


# =================================================================================================
# Unreal Engine: constants
# =================================================================================================

# UE54_CPP, file scope: "// Match the magic number in BurleyNormalizedSSSCommon.ush
#                        const float Dmfp2MfpMagicNumber = 0.6f;"
# UE58_MATH: the same 0.6 is the default argument "float Dmfp2MfpMagicNumber = 0.6f".
DMFP2MFP_MAGIC_NUMBER = 0.6
# UE54_CPP, FSubsurfaceProfileTexture::CreateTexture: "const float CmToMm = 10.f;"
CM_TO_MM = 10.0
MM_TO_CM = 0.1
# UE54_CPP, CreateTexture: "const float Bias = 0.009f;"
BIAS = 0.009
# UE54_CPP (file scope, "Consistent in BurleyNormalizedSSSCommon.ush and SubsurfaceProfile.cpp"):
#   "#define ENC_WORLDUNITSCALE_IN_CM_TO_UNIT 0.02f"
#   "#define DEC_UNIT_TO_WORLDUNITSCALE_IN_CM 1/ENC_WORLDUNITSCALE_IN_CM_TO_UNIT"
#   "#define ENC_DIFFUSEMEANFREEPATH_IN_MM_TO_UNIT (0.01f*0.2f)"
#   "#define DEC_UNIT_TO_DIFFUSEMEANFREEPATH_IN_MM 1/ENC_DIFFUSEMEANFREEPATH_IN_MM_TO_UNIT"
ENC_WORLDUNITSCALE_IN_CM_TO_UNIT = 0.02
DEC_UNIT_TO_WORLDUNITSCALE_IN_CM = 1.0 / ENC_WORLDUNITSCALE_IN_CM_TO_UNIT  # 50
ENC_DIFFUSEMEANFREEPATH_IN_MM_TO_UNIT = 0.01 * 0.2
DEC_UNIT_TO_DIFFUSEMEANFREEPATH_IN_MM = 1.0 / ENC_DIFFUSEMEANFREEPATH_IN_MM_TO_UNIT  # 500 mm
# UE5_COMMON: "#define BURLEY_MM_2_CM 0.1f" / "#define BURLEY_CM_2_MM 10.0f"
BURLEY_MM_2_CM = 0.1
BURLEY_CM_2_MM = 10.0
# UE54_H: "static const int32 SUBSURFACE_KERNEL_SIZE = 3;" (also in the shaders)
SUBSURFACE_KERNEL_SIZE = 3
# UE54_H, FSubsurfaceProfileStruct UPROPERTY metadata (editor / property-system clamps):
#   SurfaceAlbedo         meta=(ClampMin = "0.01",  UIMax = "1.0",  ClampMax = "1.0")
#   MeanFreePathColor     meta=(ClampMin = "0.001", UIMax = "1.0",  ClampMax = "1.0")
#   MeanFreePathDistance  meta=(ClampMin = "0.1",   UIMax = "50.0", ClampMax = "50.0")  "(cm)"
#   WorldUnitScale        meta=(ClampMin = "0.1",   UIMax = "50.0", ClampMax = "50.0")
#   constructor: "WorldUnitScale = 0.1f;"
META_CLAMP = {
    "SurfaceAlbedo": (0.01, 1.0),
    "MeanFreePathColor": (0.001, 1.0),
    "MeanFreePathDistance": (0.1, 50.0),
    "WorldUnitScale": (0.1, 50.0),
}
WORLD_UNIT_SCALE_DEFAULT = 0.1
# UE54_CPP, CreateTexture, 16-bit UNORM path:
#   "const float FloatScaleInitial = 0x10000;"
#   "const float FloatScale = GetNextSmallerPositiveFloat(FloatScaleInitial);"
#   "Dest[Pos * 4 + 0] = (uint16)(C.X * FloatScale);"
FLOAT_SCALE = struct.unpack("f", struct.pack("I", struct.unpack("I", struct.pack("f", 65536.0))[0] - 1))[0]


# =================================================================================================
# Unreal Engine: scaling factors (identical on CPU and GPU)
# =================================================================================================

def ue_get_perpendicular_scaling_factor(surface_albedo: float) -> float:
    """UE5x_BNSSS / UE58_MATH / UE5_COMMON, GetPerpendicularScalingFactor ("Method 1", 5.5 %).

    UE5x_BNSSS:  "// add abs() to match the formula in the original paper.
                  return 1.85 - SurfaceAlbedo + 7 * FMath::Pow(FMath::Abs(SurfaceAlbedo - 0.8), 3);"
    UE5_COMMON:  "float Value = abs(SurfaceAlbedo - 0.8);
                  return 1.85 - SurfaceAlbedo + 7 * Value * Value * Value;"
    (The UE4-era chenyong2github/UnrealEngine @ 377453377b87db279d021b6a5e53513e82bc3497 copy of
    BurleyNormalizedSSS.cpp had no abs(): "return 1.85 - SurfaceAlbedo + 7 * FMath::Pow(SurfaceAlbedo - 0.8, 3);")
    """
    return 1.85 - surface_albedo + 7.0 * abs(surface_albedo - 0.8) ** 3


def ue_get_diffuse_surface_scaling_factor(surface_albedo: float) -> float:
    """UE5x_BNSSS / UE58_MATH, GetDiffuseSurfaceScalingFactor ("Method 2", 3.9 %). Not used by the
    MFP->DMFP path; transcribed for completeness.
    "return 1.9 - SurfaceAlbedo + 3.5 * FMath::Pow(SurfaceAlbedo - 0.8, 2);"
    """
    return 1.9 - surface_albedo + 3.5 * (surface_albedo - 0.8) ** 2


def ue_get_search_light_diffuse_scaling_factor(surface_albedo: float) -> float:
    """UE5x_BNSSS / UE58_MATH / UE5_COMMON, GetSearchLightDiffuseScalingFactor ("Method 3", 7.7 %).
    UE5x_BNSSS: "return 3.5 + 100 * FMath::Pow(SurfaceAlbedo - 0.33, 4);"
    UE5_COMMON: "float Value = SurfaceAlbedo - 0.33; return 3.5 + 100 * Value * Value * Value * Value;"
    UE5_COMMON selects it for rendering: "#define LIGHT_PERPENDICULAR_DIFFUSE_SURFACE 1" ->
    GetScalingFactor3D() returns GetSearchLightDiffuseScalingFactor3D(SurfaceAlbedo).
    """
    return 3.5 + 100.0 * (surface_albedo - 0.33) ** 4


def ue54_get_diffuse_mean_free_path_from_mean_free_path(surface_albedo, mean_free_path):
    """UE5x_BNSSS (5.1-5.7), GetDiffuseMeanFreePathFromMeanFreePath (no magic number inside):
    "return MeanFreePath * FLinearColor(GetSearchLightDiffuseScalingFactor(SurfaceAlbedo) /
                                        GetPerpendicularScalingFactor(SurfaceAlbedo));"
    """
    return [mean_free_path[c] * (ue_get_search_light_diffuse_scaling_factor(surface_albedo[c])
                                 / ue_get_perpendicular_scaling_factor(surface_albedo[c])) for c in RGB]


def ue54_get_mean_free_path_from_diffuse_mean_free_path(surface_albedo, diffuse_mean_free_path):
    """UE5x_BNSSS (5.1-5.7), GetMeanFreePathFromDiffuseMeanFreePath:
    "return DiffuseMeanFreePath * FLinearColor(GetPerpendicularScalingFactor(SurfaceAlbedo) /
                                               GetSearchLightDiffuseScalingFactor(SurfaceAlbedo));"
    """
    return [diffuse_mean_free_path[c] * (ue_get_perpendicular_scaling_factor(surface_albedo[c])
                                         / ue_get_search_light_diffuse_scaling_factor(surface_albedo[c]))
            for c in RGB]


def ue58_get_diffuse_mean_free_path_from_mean_free_path(surface_albedo, mean_free_path,
                                                         dmfp2mfp_magic_number=DMFP2MFP_MAGIC_NUMBER):
    """UE58_MATH, SubsurfaceScattering::BurleyNormalized::GetDiffuseMeanFreePathFromMeanFreePath:
    "return MeanFreePath * FLinearColor(GetSearchLightDiffuseScalingFactor(SurfaceAlbedo) /
                                        (GetPerpendicularScalingFactor(SurfaceAlbedo) * Dmfp2MfpMagicNumber));"
    """
    return [mean_free_path[c] * (ue_get_search_light_diffuse_scaling_factor(surface_albedo[c])
                                 / (ue_get_perpendicular_scaling_factor(surface_albedo[c]) * dmfp2mfp_magic_number))
            for c in RGB]


def ue58_get_mean_free_path_from_diffuse_mean_free_path(surface_albedo, diffuse_mean_free_path,
                                                         dmfp2mfp_magic_number=DMFP2MFP_MAGIC_NUMBER):
    """UE58_MATH, GetMeanFreePathFromDiffuseMeanFreePath:
    "return DiffuseMeanFreePath * FLinearColor(GetPerpendicularScalingFactor(SurfaceAlbedo) /
             GetSearchLightDiffuseScalingFactor(SurfaceAlbedo)) * Dmfp2MfpMagicNumber;"
    """
    return [diffuse_mean_free_path[c] * (ue_get_perpendicular_scaling_factor(surface_albedo[c])
                                         / ue_get_search_light_diffuse_scaling_factor(surface_albedo[c]))
            * dmfp2mfp_magic_number for c in RGB]


# =================================================================================================
# Unreal Engine: asset fields -> profile texture row (CPU)
# =================================================================================================

def ue_get_clamped(color, in_min=0.0, in_max=1.0):
    """FLinearColor::GetClamped(float InMin = 0.0f, float InMax = 1.0f) (Core Math/Color.h):
    "Ret.R = FMath::Clamp(R, InMin, InMax); ..." (RGB only here)."""
    return [min(max(color[c], in_min), in_max) for c in RGB]


def ue_setup_surface_albedo_and_diffuse_mean_free_path(surface_albedo, dmfp, sampling_selection_method=1):
    """UE54_CPP, SetupSurfaceAlbedoAndDiffuseMeanFreePath (r.SSProfilesSamplingChannelSelection, default 1):
    "FLinearColor Distance = SamplingSelectionMethod == 0 ? Dmfp
                             : GetMeanFreePathFromDiffuseMeanFreePath(SurfaceAlbedo, Dmfp);
     const float MaxComp = FMath::Max3(Distance.R, Distance.G, Distance.B);
     const uint32 IndexOfMaxComp = (Distance.R == MaxComp) ? 0 : ((Distance.G == MaxComp) ? 1 : 2);
     SurfaceAlbedo.A = SurfaceAlbedo.Component(IndexOfMaxComp);
     Dmfp.A = Dmfp.Component(IndexOfMaxComp);
     // Apply clamping so that dmfp is within encoding range.
     Dmfp = Dmfp.GetClamped(0.0f, DEC_UNIT_TO_DIFFUSEMEANFREEPATH_IN_MM);"
    The .A channels only choose the channel used for importance sampling in the shader; they do
    not change any channel's profile. Returns (albedo_rgba, dmfp_rgba).
    """
    distance = dmfp if sampling_selection_method == 0 else \
        ue54_get_mean_free_path_from_diffuse_mean_free_path(surface_albedo, dmfp)
    max_comp = max(distance)
    index = 0 if distance[0] == max_comp else (1 if distance[1] == max_comp else 2)
    albedo_a = surface_albedo[index]
    dmfp_a = dmfp[index]
    dmfp_rgba = [min(max(v, 0.0), DEC_UNIT_TO_DIFFUSEMEANFREEPATH_IN_MM) for v in list(dmfp) + [dmfp_a]]
    return list(surface_albedo) + [albedo_a], dmfp_rgba


def ue_create_texture_row(surface_albedo, mean_free_path_color, mean_free_path_distance,
                          world_unit_scale=WORLD_UNIT_SCALE_DEFAULT, b_enable_mean_free_path=True,
                          version="5.4"):
    """UE54_CPP (and UE58_CPP), FSubsurfaceProfileTexture::CreateTexture, the Burley part of one row:

    "Data.MeanFreePathColor = Data.MeanFreePathColor.GetClamped(Bias); // In Cm
     Data.SurfaceAlbedo = Data.SurfaceAlbedo.GetClamped(Bias);
     TextureRow[SSSS_TINT_SCALE_OFFSET].A = EncodeWorldUnitScale(Data.WorldUnitScale);
     if (Data.bEnableMeanFreePath)
         DifffuseMeanFreePathInMm = GetDiffuseMeanFreePathFromMeanFreePath(Data.SurfaceAlbedo,
             Data.MeanFreePathColor * Data.MeanFreePathDistance) * CmToMm / Dmfp2MfpMagicNumber;   [5.4]
         DifffuseMeanFreePathInMm = SubsurfaceScattering::BurleyNormalized::
             GetDiffuseMeanFreePathFromMeanFreePath(Data.SurfaceAlbedo,
             Data.MeanFreePathColor * Data.MeanFreePathDistance) * CmToMm;                          [5.8]
     else
         DifffuseMeanFreePathInMm = (Data.MeanFreePathColor * Data.MeanFreePathDistance) * CmToMm;
     SetupSurfaceAlbedoAndDiffuseMeanFreePath(Data.SurfaceAlbedo, DifffuseMeanFreePathInMm);
     TextureRow[BSSS_SURFACEALBEDO_OFFSET] = Data.SurfaceAlbedo;
     TextureRow[BSSS_DMFP_OFFSET] = EncodeDiffuseMeanFreePath(DifffuseMeanFreePathInMm);"

    The UPROPERTY meta clamps (META_CLAMP) are NOT applied here: CreateTexture does not apply
    them; the editor/property system does when a value is typed in or imported.
    Returns the float row values (before 16-bit quantization).
    """
    mfp_color = ue_get_clamped(mean_free_path_color, BIAS)
    albedo = ue_get_clamped(surface_albedo, BIAS)
    mfp = [mfp_color[c] * mean_free_path_distance for c in RGB]
    if b_enable_mean_free_path:
        if version == "5.8":
            dmfp_mm = [v * CM_TO_MM for v in ue58_get_diffuse_mean_free_path_from_mean_free_path(albedo, mfp)]
        else:
            dmfp_mm = [v * CM_TO_MM / DMFP2MFP_MAGIC_NUMBER
                       for v in ue54_get_diffuse_mean_free_path_from_mean_free_path(albedo, mfp)]
    else:
        dmfp_mm = [v * CM_TO_MM for v in mfp]
    albedo_rgba, dmfp_rgba = ue_setup_surface_albedo_and_diffuse_mean_free_path(albedo, dmfp_mm)
    return {
        "surface_albedo_rgba": albedo_rgba,
        "dmfp_mm_rgba": dmfp_rgba,
        "encoded_dmfp_rgba": ue_encode_diffuse_mean_free_path(dmfp_rgba),
        "encoded_world_unit_scale": ue_encode_world_unit_scale(world_unit_scale),
    }


def ue_encode_world_unit_scale(world_unit_scale):
    """UE54_CPP, EncodeWorldUnitScale: "return WorldUnitScale * ENC_WORLDUNITSCALE_IN_CM_TO_UNIT;" """
    return world_unit_scale * ENC_WORLDUNITSCALE_IN_CM_TO_UNIT


def ue_decode_world_unit_scale(encoded):
    """UE5_COMMON / UE54_CPP, DecodeWorldUnitScale: "return EncodedWorldUnitScale * DEC_UNIT_TO_WORLDUNITSCALE_IN_CM;" """
    return encoded * DEC_UNIT_TO_WORLDUNITSCALE_IN_CM


def ue_encode_diffuse_mean_free_path(dmfp):
    """UE54_CPP, EncodeDiffuseMeanFreePath: "return DiffuseMeanFreePath * ENC_DIFFUSEMEANFREEPATH_IN_MM_TO_UNIT;" """
    return [v * ENC_DIFFUSEMEANFREEPATH_IN_MM_TO_UNIT for v in dmfp]


def ue_decode_diffuse_mean_free_path(encoded):
    """UE5_COMMON, DecodeDiffuseMeanFreePath: "return EncodedDiffuseMeanFreePath * DEC_UNIT_TO_DIFFUSEMEANFREEPATH_IN_MM;" """
    return [v * DEC_UNIT_TO_DIFFUSEMEANFREEPATH_IN_MM for v in encoded]


def ue_quantize_unorm16(value):
    """UE54_CPP, CreateTexture, b16Bit / UNORM path (PF_A16B16G16R16):
    "Dest[Pos * 4 + 0] = (uint16)(C.X * FloatScale);"  (truncation), read back by the GPU as
    UNORM16 = uint16 / 65535. (Platforms where PF_A16B16G16R16 maps to RGBA16F take the
    "bUseRGBA16F" branch and additionally round to half; not transcribed.)"""
    c = f32(value)
    q = int(f32(c * FLOAT_SCALE))
    q = max(0, min(q, 0xFFFF))
    return q / 65535.0


# =================================================================================================
# Unreal Engine: what the screen-space Burley pass renders (GPU)
# =================================================================================================

def ue_get_burley_parameters(albedo_rgba, encoded_dmfp_rgba, encoded_world_unit_scale, surface_opacity=1.0):
    """UE54_USF, GetBurleyParameters (non-Strata branch):
    "Out.SurfaceAlbedo = GetSubsurfaceProfileSurfaceAlbedo(SubsurfaceProfileInt);
     Out.DiffuseMeanFreePath = DecodeDiffuseMeanFreePath(GetSubsurfaceProfileDiffuseMeanFreePath(SubsurfaceProfileInt));
     Out.WorldUnitScale = DecodeWorldUnitScale(GetSubsurfaceProfileWorldUnitScale(SubsurfaceProfileInt)) * BURLEY_CM_2_MM;
     Out.SurfaceOpacity = UseSubsurfaceProfile(GBuffer.ShadingModelID) ? GBuffer.CustomData.a : 0.0f;
     Out.DiffuseMeanFreePath *= Out.SurfaceOpacity;"
    surface_opacity is the material's Opacity input (GBuffer CustomData.a); 1 = profile as authored.
    """
    dmfp = ue_decode_diffuse_mean_free_path(encoded_dmfp_rgba)
    return {
        "SurfaceAlbedo": list(albedo_rgba),
        "DiffuseMeanFreePath": [v * surface_opacity for v in dmfp],
        "WorldUnitScale": ue_decode_world_unit_scale(encoded_world_unit_scale) * BURLEY_CM_2_MM,
        "SurfaceOpacity": surface_opacity,
    }


def ue_get_diffuse_reflect_profile_with_diffuse_mean_free_path(L, S3D, radius):
    """UE5_COMMON, GetDiffuseReflectProfileWithDiffuseMeanFreePath (called by UE54_USH BurleyNormalizedSS:
    "float3 DiffusionProfile = GetDiffuseReflectProfileWithDiffuseMeanFreePath(
         BurleyParameter.DiffuseMeanFreePath.xyz, S3D.xyz, RadiusSampledInMM);"):
    "//rR(r)
     float3 D = 1 / S3D;
     float3 R = Radius / L;
     const float Inv8Pi = 1.0 / (8 * PI);
     float3 NegRbyD = -R / D;
     return max((exp(NegRbyD) + exp(NegRbyD / 3.0)) / (D*L)*Inv8Pi, 0);"
    Returns r*R(r) per channel (radius in mm, L = DMFP in mm, S3D = GetScalingFactor3D(A)).
    """
    out = []
    for c in RGB:
        D = 1.0 / S3D[c]
        R = radius / L[c]
        neg_r_by_d = -R / D
        out.append(max((math.exp(neg_r_by_d) + math.exp(neg_r_by_d / 3.0)) / (D * L[c]) / (8.0 * math.pi), 0.0))
    return out


def ue_calculate_burley_scale(world_unit_scale_shader, depth_at_center, projection_m00,
                              sss_radius_scale=1.0, viewport_over_extent=1.0):
    """UE54_USH, CalculateBurleyScale (x component), with SubsurfaceParams.x from
    GetSubsurfaceCommonParameters (PostProcessSubsurface.cpp; documented in UE54_USF:
    "// x:Radius*DistanceToProjectionWindow/KernelSize*0.5"):
      C++: "const float DistanceToProjectionWindow = View.ViewMatrices.GetProjectionMatrix().M[0][0];
            const float SSSScaleZ = DistanceToProjectionWindow * GetSubsurfaceRadiusScale();
            const float SSSScaleX = SSSScaleZ / SUBSURFACE_KERNEL_SIZE * 0.5f;"
      HLSL:"float2 BurleyScale = WorldUnitScale;
            float SSSScaleX = SubsurfaceParams.x;
            BurleyScale *= SSSScaleX / DepthAtCenter;
            // cast from cm to mm for depth, and remove the effect of SUBSURFACE_KERNEL_SIZE.
            BurleyScale *= SUBSURFACE_KERNEL_SIZE / BURLEY_CM_2_MM;
            BurleyScale *= (SubsurfaceInput0_ViewportSize.x * SubsurfaceInput0_ExtentInverse.x);"
    and in BurleyNormalizedSS: "float2 UVOffset = BurleyScale*BurleySampleInfo.RadiusInMM;"
    Returns buffer-UV offset per mm of profile radius. sss_radius_scale = r.SSS.Scale (default 1).
    """
    sss_scale_z = projection_m00 * sss_radius_scale
    sss_scale_x = sss_scale_z / SUBSURFACE_KERNEL_SIZE * 0.5
    burley_scale = world_unit_scale_shader
    burley_scale *= sss_scale_x / depth_at_center
    burley_scale *= SUBSURFACE_KERNEL_SIZE / BURLEY_CM_2_MM
    burley_scale *= viewport_over_extent
    return burley_scale


def ue_world_units_per_profile_mm(world_unit_scale_asset, sss_radius_scale=1.0):
    """World distance (Unreal units) that the Burley pass maps one profile-millimetre to.

    Derived from the transcribed CalculateBurleyScale: a world offset x at view depth z moves
    buffer UV by 0.5*M[0][0]*x/z*(ViewportSize/Extent) (perspective projection), so
    x = UVOffset / that. Evaluated numerically (any depth / M00 give the same ratio)."""
    depth, m00 = 123.0, 1.7
    wus_shader = ue_decode_world_unit_scale(ue_encode_world_unit_scale(world_unit_scale_asset)) * BURLEY_CM_2_MM
    uv_per_mm = ue_calculate_burley_scale(wus_shader, depth, m00, sss_radius_scale)
    uv_per_world_unit = 0.5 * m00 / depth
    return uv_per_mm / uv_per_world_unit


def ue_rendered(surface_albedo, mean_free_path_color, mean_free_path_distance,
                world_unit_scale=WORLD_UNIT_SCALE_DEFAULT, version="5.4", quantize=False, surface_opacity=1.0):
    """Forward direction: asset fields -> per-channel Burley d (profile mm) the shader uses.

    The shader's profile is GetDiffuseReflectProfileWithDiffuseMeanFreePath(L = DMFP, S3D =
    GetSearchLightDiffuseScalingFactor3D(SurfaceAlbedo), r), i.e. exp(-r*S/L): Burley's d = L/S.
    (UE54_USH also: "float3 D = DiffuseMeanFreePath / GetScalingFactor3D(BurleyParameter.SurfaceAlbedo.xyz);"
    in CalculateCenterSampleWeight.) The accumulated samples are divided by their summed weights
    ("RadianceAccumulated.xyz *= ... 1.0f /WeightingFactor*EnergyNormalization"), so the profile
    is used normalized; the material BaseColor is applied afterwards in SubsurfaceRecombinePS
    (DeferredShadingCommon.ush AdjustBaseColorAndSpecularColorForSubsurfaceProfileLighting:
    "// we apply the base color later in SubsurfaceRecombinePS()").
    """
    row = ue_create_texture_row(surface_albedo, mean_free_path_color, mean_free_path_distance,
                                world_unit_scale, True, version)
    albedo_rgba = row["surface_albedo_rgba"]
    enc = row["encoded_dmfp_rgba"]
    enc_wus = row["encoded_world_unit_scale"]
    if quantize:
        albedo_rgba = [ue_quantize_unorm16(v) for v in albedo_rgba]
        enc = [ue_quantize_unorm16(v) for v in enc]
        enc_wus = ue_quantize_unorm16(enc_wus)
    params = ue_get_burley_parameters(albedo_rgba, enc, enc_wus, surface_opacity)
    s3d = [ue_get_search_light_diffuse_scaling_factor(params["SurfaceAlbedo"][c]) for c in RGB]
    L = params["DiffuseMeanFreePath"][:3]
    d_mm = [L[c] / s3d[c] for c in RGB]
    wu_per_mm = ue_world_units_per_profile_mm(ue_decode_world_unit_scale(enc_wus) if quantize else world_unit_scale)
    return {
        "dmfp_mm": L,
        "scaling_factor_S3D": s3d,
        "burley_d_profile_mm": d_mm,
        "world_units_per_profile_mm": wu_per_mm,
        # 1 Unreal unit = 1 cm = 10 mm: the profile's d as a length on the rendered surface
        "burley_d_world_mm_if_unit_is_cm": [v * wu_per_mm * 10.0 for v in d_mm],
        "shader_WorldUnitScale": params["WorldUnitScale"],
        "sampling_channel_albedo_A": albedo_rgba[3],
        "sampling_channel_dmfp_A_mm": params["DiffuseMeanFreePath"][3],
    }


def ue_rendered_profile_R(r_mm, d_mm):
    """Normalized per-channel profile R(r)/A the Burley pass integrates (mm^-2): the transcribed
    rR(r) divided by r, with L/S = d (the same expression, rearranged)."""
    return [ue_get_diffuse_reflect_profile_with_diffuse_mean_free_path([d_mm[c]] * 3, [1.0] * 3, r_mm)[0] / r_mm
            for c in RGB]


def ue_fields_for_burley(a_rgb, d_mm_rgb, world_unit_scale=WORLD_UNIT_SCALE_DEFAULT, version="5.4"):
    """Inverse direction (not engine code: the inversion of ue_create_texture_row + ue_rendered).

    d = DMFP/S_sl(A) and DMFP = MFP * S_sl(A)/S_perp(A) * CmToMm / 0.6, so for SurfaceAlbedo = A
    (inside [Bias, 1]) MFP_cm = d_mm * 0.6 * S_perp(A) / CmToMm. MeanFreePathDistance =
    max MFP, MeanFreePathColor = MFP / max; if the max is below the UPROPERTY ClampMin 0.1 the
    distance is set to 0.1 and the colour scaled down (the same move UE's own
    UpgradeDiffuseMeanFreePathToMeanFreePath makes for "Support mfp < 0.1f"). The result is
    re-run through the forward chain and the round-trip error reported.
    """
    mfp_cm = [d_mm_rgb[c] * DMFP2MFP_MAGIC_NUMBER * ue_get_perpendicular_scaling_factor(a_rgb[c]) / CM_TO_MM
              for c in RGB]
    dist = max(mfp_cm)
    color = [v / dist for v in mfp_cm]
    notes = []
    lo, hi = META_CLAMP["MeanFreePathDistance"]
    if dist < lo:
        color = [v * (dist / lo) for v in color]
        dist = lo
        notes.append("max MFP below MeanFreePathDistance ClampMin 0.1 cm: distance set to 0.1, colour scaled")
    if dist > hi:
        notes.append("MeanFreePathDistance above ClampMax 50 cm: not representable")
    if any(v < BIAS for v in color):
        notes.append("a MeanFreePathColor channel < 0.009: CreateTexture clamps it (Bias), d changes")
    if any(v < BIAS for v in a_rgb):
        notes.append("a SurfaceAlbedo channel < 0.009: CreateTexture clamps it (Bias), d changes")
    if any(v < META_CLAMP["SurfaceAlbedo"][0] for v in a_rgb):
        notes.append("a SurfaceAlbedo channel < UPROPERTY ClampMin 0.01")
    fields = {
        "bEnableBurley": True,
        "bEnableMeanFreePath": True,
        "SurfaceAlbedo": list(a_rgb),
        "MeanFreePathColor": color,
        "MeanFreePathDistance": dist,
        "WorldUnitScale": world_unit_scale,
    }
    fwd = ue_rendered(a_rgb, color, dist, world_unit_scale, version)
    fwd_q = ue_rendered(a_rgb, color, dist, world_unit_scale, version, quantize=True)
    return {
        "fields": fields,
        "mean_free_path_cm_rgb": mfp_cm,
        "forward": fwd,
        "forward_rel_error_d": [fwd["burley_d_profile_mm"][c] / d_mm_rgb[c] - 1 for c in RGB],
        "forward_16bit_texture": fwd_q,
        "forward_16bit_rel_error_d": [fwd_q["burley_d_profile_mm"][c] / d_mm_rgb[c] - 1 for c in RGB],
        "forward_16bit_rel_error_d_world": [fwd_q["burley_d_world_mm_if_unit_is_cm"][c] / d_mm_rgb[c] - 1
                                            for c in RGB],
        "notes": notes,
    }


# =================================================================================================
# Unity HDRP
# =================================================================================================

HDRP_MILLIMETERS_PER_METER = 1000.0  # Core ShaderLibrary MILLIMETERS_PER_METER, used in HDRP_SSS EvaluateSss


def hdrp_convert_hdr_color_to_ldr(hdr):
    """HDRP_UTIL, HDUtils.ConvertHDRColorToLDR (used by the DiffusionProfileSettings.scatteringDistance
    setter and by the SplitScatteringDistance migration):
    "const float k_MaxByteForOverexposedColor = 191;
     ...
     var maxColorComponent = hdr.maxColorComponent;
     if (maxColorComponent != 0f)
     {
         var scaleFactor = k_MaxByteForOverexposedColor / maxColorComponent;
         ldr.r = Mathf.Min(k_MaxByteForOverexposedColor, scaleFactor * hdr.r) / 255f;
         ...
         intensity = 255f / scaleFactor;
     }"
    """
    k_max_byte = 191.0
    ldr = list(hdr)
    intensity = 1.0
    m = max(hdr)
    if m != 0.0:
        scale_factor = k_max_byte / m
        ldr = [min(k_max_byte, scale_factor * v) / 255.0 for v in hdr]
        intensity = 255.0 / scale_factor
    return ldr, intensity


def hdrp_sample_burley_diffusion_profile_cs(u, rcp_s):
    """HDRP_CS, DiffusionProfile.SampleBurleyDiffusionProfile (C#):
    "u = 1 - u; // Convert CDF to CCDF
     float g = 1 + (4 * u) * (2 * u + Mathf.Sqrt(1 + (4 * u) * u));
     float n = Mathf.Pow(g, -1.0f / 3.0f);                      // g^(-1/3)
     float p = (g * n) * n;                                   // g^(+1/3)
     float c = 1 + p + n;                                     // 1 + g^(+1/3) + g^(-1/3)
     float x = 3 * Mathf.Log(c / (4 * u));
     return x * rcpS;"
    """
    u = 1.0 - u
    g = 1.0 + (4.0 * u) * (2.0 * u + math.sqrt(1.0 + (4.0 * u) * u))
    n = g ** (-1.0 / 3.0)
    p = (g * n) * n
    c = 1.0 + p + n
    x = 3.0 * math.log(c / (4.0 * u))
    return x * rcp_s


def hdrp_update_kernel(scattering_distance, scattering_distance_multiplier):
    """HDRP_CS, DiffusionProfile.UpdateKernel:
    "Vector3 sd = scatteringDistanceMultiplier * (Vector3)(Vector4)scatteringDistance;
     // Rather inconvenient to support (S = Inf).
     shapeParam = new Vector3(Mathf.Min(16777216, 1.0f / sd.x),
                              Mathf.Min(16777216, 1.0f / sd.y),
                              Mathf.Min(16777216, 1.0f / sd.z));
     float cdf = 0.997f;
     maxScatteringDistance = Mathf.Max(sd.x, sd.y, sd.z);
     filterRadius = SampleBurleyDiffusionProfile(cdf, maxScatteringDistance);"
    Field comments: "public Vector3 shapeParam // RGB = shape parameter: S = 1 / D",
                    "public float filterRadius // In millimeters".
    """
    sd = [scattering_distance_multiplier * scattering_distance[c] for c in RGB]
    shape = [min(16777216.0, 1.0 / v) if v != 0.0 else 16777216.0 for v in sd]
    max_sd = max(sd)
    filter_radius = hdrp_sample_burley_diffusion_profile_cs(0.997, max_sd)
    return {"sd": sd, "shapeParam": shape, "maxScatteringDistance": max_sd, "filterRadius": filter_radius}


def hdrp_validate(world_scale, ior):
    """HDRP_CS, DiffusionProfile.Validate (fields relevant here):
    "worldScale = Mathf.Max(worldScale, 0.001f);  ior = Mathf.Clamp(ior, 1.0f, 2.0f);" """
    return max(world_scale, 0.001), min(max(ior, 1.0), 2.0)


def hdrp_disney_profile(r, s):
    """HDRP_CS, DiffusionProfile.DisneyProfile:
    "return s * (Mathf.Exp(-r * s) + Mathf.Exp(-r * s * (1.0f / 3.0f))) / (8.0f * Mathf.PI * r);" """
    return s * (math.exp(-r * s) + math.exp(-r * s * (1.0 / 3.0))) / (8.0 * math.pi * r)


def hdrp_eval_burley_diffusion_profile(r, S):
    """HDRP_HLSL, EvalBurleyDiffusionProfile ("The result must be multiplied by the albedo"):
    "float3 exp_13 = exp2(((LOG2_E * (-1.0/3.0)) * r) * S); // Exp[-S * r / 3]
     float3 expSum = exp_13 * (1 + exp_13 * exp_13);        // Exp[-S * r / 3] + Exp[-S * r]
     return (S * rcp(8 * PI)) * expSum;"
    Polar form r*R(r) (no 1/r), r in mm."""
    out = []
    for c in RGB:
        e13 = math.exp(-S[c] * r / 3.0)
        out.append(S[c] / (8.0 * math.pi) * (e13 * (1.0 + e13 * e13)))
    return out


def hdrp_mm_per_unit(meters_per_unit, subsurface_mask=1.0):
    """HDRP_SSS, EvaluateSss:
    "float  distScale = sssData.subsurfaceMask;
     float  metersPerUnit = _WorldScalesAndFilterRadiiAndThicknessRemaps[profileIndex].x;
     // Rescaling the filter is equivalent to inversely scaling the world.
     float mmPerUnit = MILLIMETERS_PER_METER * (metersPerUnit * rcp(distScale));"
    (and "if (distScale == 0 || sampleCount < 1)" -> no scattering)."""
    return HDRP_MILLIMETERS_PER_METER * (meters_per_unit / subsurface_mask)


def hdrp_rendered(scattering_distance, scattering_distance_multiplier, world_scale=1.0, subsurface_mask=1.0):
    """Forward direction: profile fields -> per-channel d.

    The compute shader samples r (mm) with SampleBurleyDiffusionProfile(.., d = maxScatteringDistance),
    weights each sample by EvalBurleyDiffusionProfile(r, S) * rcpPdf and divides by the summed
    weights ("result.irradiance = albedo * (totalIrradiance / totalWeight);"), i.e. it renders the
    normalized profile S*(e^{-Sr}+e^{-Sr/3})/(8 pi r) times the material albedo. Profile mm are
    converted to world units with mmPerUnit, so in real millimetres (1 unit = worldScale m)
    d_world_mm = subsurfaceMask / S.
    """
    k = hdrp_update_kernel(scattering_distance, scattering_distance_multiplier)
    mm_per_unit = hdrp_mm_per_unit(world_scale, subsurface_mask)
    d_profile_mm = [1.0 / s for s in k["shapeParam"]]
    d_world_mm = [v / mm_per_unit * 1000.0 * world_scale for v in d_profile_mm]
    return {
        "shapeParam_per_mm": k["shapeParam"],
        "burley_d_profile_mm": d_profile_mm,
        "burley_d_world_mm": d_world_mm,
        "maxScatteringDistance_mm": k["maxScatteringDistance"],
        "filterRadius_mm": k["filterRadius"],
        "mmPerUnit": mm_per_unit,
    }


def hdrp_rendered_profile_R(r_mm, shape_param):
    """Normalized per-channel profile R(r)/albedo HDRP integrates (mm^-2): DisneyProfile(r, S)."""
    return [hdrp_disney_profile(r_mm, shape_param[c]) for c in RGB]


def hdrp_fields_for_burley(d_mm_rgb):
    """Inverse direction (not engine code): S = 1/d, so scatteringDistance*multiplier = d (mm).
    Split the HDR colour d the way HDRP's own setter does (ConvertHDRColorToLDR); the
    max-normalised split (colour max = 1) is given too: UpdateKernel only uses the product."""
    ldr, mult = hdrp_convert_hdr_color_to_ldr(d_mm_rgb)
    m = max(d_mm_rgb)
    alt_color = [v / m for v in d_mm_rgb]
    fwd = hdrp_rendered(ldr, mult)
    fwd_alt = hdrp_rendered(alt_color, m)
    return {
        "fields_hdutils_split": {
            "scatteringDistance": ldr, "scatteringDistanceMultiplier": mult, "worldScale": 1.0,
            "texturingMode": "PreAndPostScatter", "transmissionMode": "ThinObject",
            "thicknessRemap": [0.0, 5.0], "transmissionTint": [1.0, 1.0, 1.0],
        },
        "fields_max_normalised_split": {"scatteringDistance": alt_color, "scatteringDistanceMultiplier": m},
        "material_requirements": {"diffuseColor": "A (HDRP applies the albedo after the normalized blur)",
                                  "subsurfaceMask": 1.0},
        "forward": fwd,
        "forward_rel_error_d": [fwd["burley_d_world_mm"][c] / d_mm_rgb[c] - 1 for c in RGB],
        "forward_max_normalised_split": fwd_alt,
    }


# =================================================================================================
# NOT ENGINE CODE: the exporter's claim, for comparison only (baker/src/export/burley/conventions.rs
# unreal_mfp_cm doc comment: "MFP_cm = 0.06·s_perp(A)·d_mm"). Not used by anything above.
# =================================================================================================

def exporter_claim_unreal_mfp_cm(a, d_mm):
    return 0.06 * (1.85 - a + 7.0 * abs(a - 0.8) ** 3) * d_mm


# =================================================================================================

CASES = [
    {"name": "case1", "A": [0.85, 0.55, 0.35], "d_mm": [1.2, 0.6, 0.3]},
    {"name": "case2", "A": [0.6, 0.3, 0.15], "d_mm": [0.8, 0.35, 0.2]},
]


def build_pinned():
    out = {
        "about": "Engine-side fields and their forward evaluation, computed by validation/engine_reference/"
                 "engine_sss.py (transcription of UE 5.4/5.8 and HDRP source; see README.md). Lengths in "
                 "mm unless named _cm. d = Burley shape parameter of R(r) = A (e^{-r/d}+e^{-r/3d})/(8 pi d r).",
        "unreal_assumptions": {
            "WorldUnitScale": WORLD_UNIT_SCALE_DEFAULT, "r.SSS.Scale": 1.0,
            "r.SSProfilesSamplingChannelSelection": 1, "material_Opacity": 1.0,
            "material_BaseColor": "A (UE applies BaseColor in SubsurfaceRecombinePS; the Burley kernel is normalized)",
            "world_unit": "1 Unreal unit = 1 cm",
        },
        "unity_assumptions": {"worldScale_m_per_unit": 1.0, "subsurfaceMask": 1.0},
        "cases": [],
    }
    for case in CASES:
        a, d = case["A"], case["d_mm"]
        ue54 = ue_fields_for_burley(a, d, version="5.4")
        ue58 = ue_fields_for_burley(a, d, version="5.8")
        hd = hdrp_fields_for_burley(d)
        out["cases"].append({
            "name": case["name"],
            "burley_A": a,
            "burley_d_mm": d,
            "unreal_5_4": ue54,
            "unreal_5_8_forward_of_same_fields": ue58["forward"],
            "unreal_5_8_fields_identical_to_5_4": ue58["fields"] == ue54["fields"],
            "hdrp": hd,
            "profile_samples": {
                "r_mm": [0.1, 0.5, 1.0, 2.0],
                "unreal_R_over_A_per_mm2": [ue_rendered_profile_R(r, ue54["forward"]["burley_d_profile_mm"])
                                            for r in (0.1, 0.5, 1.0, 2.0)],
                "hdrp_R_over_A_per_mm2": [hdrp_rendered_profile_R(r, hd["forward"]["shapeParam_per_mm"])
                                          for r in (0.1, 0.5, 1.0, 2.0)],
            },
            "comparison_exporter_claim_mfp_cm_NOT_ENGINE": [exporter_claim_unreal_mfp_cm(a[c], d[c]) for c in RGB],
        })
    return out


def _self_check():
    # Unreal's own default skin (UE54_H constructor), DMFP mode upgraded to MFP by
    # UpgradeDiffuseMeanFreePathToMeanFreePath (UE54_CPP):
    #   "FLinearColor Mfp = GetMeanFreePathFromDiffuseMeanFreePath(Settings.SurfaceAlbedo, OldDmfp);
    #    Mfp *= Dmfp2MfpMagicNumber;"
    # The upgraded profile must render the old DMFP (cm -> mm) exactly.
    sa = [0.91058, 0.338275, 0.2718]
    col = [1.0, 0.1983 / 2.229, 0.1607 / 2.229]
    dist = 1.2 * 2.229
    old_dmfp_cm = [c * dist for c in col]
    mfp = [v * DMFP2MFP_MAGIC_NUMBER for v in ue54_get_mean_free_path_from_diffuse_mean_free_path(sa, old_dmfp_cm)]
    mfp_dist = max(mfp)
    mfp_col = [v / mfp_dist for v in mfp]
    for version in ("5.4", "5.8"):
        fwd = ue_rendered(sa, mfp_col, mfp_dist, version=version)
        for c in RGB:
            assert abs(fwd["dmfp_mm"][c] / (old_dmfp_cm[c] * 10.0) - 1) < 1e-12, (version, c)
    # 5.8's folded magic number equals 5.4's explicit division.
    x = ue58_get_diffuse_mean_free_path_from_mean_free_path(sa, mfp)
    y = [v / DMFP2MFP_MAGIC_NUMBER for v in ue54_get_diffuse_mean_free_path_from_mean_free_path(sa, mfp)]
    assert all(abs(x[c] / y[c] - 1) < 1e-12 for c in RGB)
    # At WorldUnitScale 0.1 one profile mm is 0.1 world unit (= 1 mm if 1 unit = 1 cm).
    assert abs(ue_world_units_per_profile_mm(0.1) - 0.1) < 1e-12
    # HDRP: the sampled 99.7 % radius inverts the CDF 1 - e^{-r/d}/4 - 3 e^{-r/3d}/4.
    d = 0.7
    r = hdrp_sample_burley_diffusion_profile_cs(0.997, d)
    assert abs(1 - 0.25 * math.exp(-r / d) - 0.75 * math.exp(-r / (3 * d)) - 0.997) < 1e-12
    # HDRP's setter split multiplies back to the HDR colour.
    ldr, k = hdrp_convert_hdr_color_to_ldr([1.2, 0.6, 0.3])
    assert all(abs(ldr[c] * k / [1.2, 0.6, 0.3][c] - 1) < 1e-12 for c in RGB)


if __name__ == "__main__":
    _self_check()
    pinned = build_pinned()
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "pinned.json")
    with open(path, "w") as fh:
        json.dump(pinned, fh, indent=2)
        fh.write("\n")
    print("wrote", path)
