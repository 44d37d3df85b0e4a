// Byte layout of trace format v1 (binary), as specified in traces/FORMAT.md.
// Shared by the reader, the writer and tools that inspect files.
#pragma once

#include <cstddef>
#include <cstdint>

#include "traces/Fragment.hpp"

namespace oit::format_v1 {

// "\x89OITT\r\n\x1A": the non-ASCII first byte keeps text tools from taking the
// file for text, and CR LF / ^Z catch text-mode line-ending conversion.
inline constexpr unsigned char kMagic[8] = {0x89, 'O', 'I', 'T', 'T', '\r', '\n', 0x1A};
inline constexpr uint32_t kVersion = 1;
// Version 2 = version 1 + a draw state table after the draw table (section 3.1);
// written only for traces whose draws carry a DrawState (apitrace captures).
inline constexpr uint32_t kVersion2 = 2;

// Fixed header: 64 bytes.
inline constexpr size_t kFixedHeaderBytes = 64;
inline constexpr size_t kOffMagic = 0;          // u8[8]
inline constexpr size_t kOffVersion = 8;        // u32
inline constexpr size_t kOffHeaderBytes = 12;   // u32, offset of record 0
inline constexpr size_t kOffWidth = 16;         // u32
inline constexpr size_t kOffHeight = 20;        // u32
inline constexpr size_t kOffFragmentCount = 24; // u64
inline constexpr size_t kOffEncoding = 32;      // u32, ColourEncoding
inline constexpr size_t kOffRecordBytes = 36;   // u32, 32 or 20
inline constexpr size_t kOffFlags = 40;         // u32
inline constexpr size_t kOffCameraNear = 44;    // f32
inline constexpr size_t kOffCameraFar = 48;     // f32
inline constexpr size_t kOffDrawCount = 52;     // u32
inline constexpr size_t kOffReserved = 56;      // u8[8], zero
inline constexpr size_t kReservedBytes = 8;

inline constexpr uint32_t kFlagCamera = 1u << 0;
inline constexpr uint32_t kKnownFlags = kFlagCamera;

// fragment_count while a writer is still writing; commit() patches the real count.
inline constexpr uint64_t kUnfinishedCount = UINT64_MAX;

// Draw table entries: 64 bytes each, right after the fixed header.
inline constexpr size_t kDrawEntryBytes = 64;
inline constexpr size_t kDrawOffId = 0;     // u32
inline constexpr size_t kDrawOffClass = 4;  // u32, DrawClass
inline constexpr size_t kDrawOffName = 8;   // u8[56], NUL-padded
inline constexpr size_t kDrawNameField = 56;
inline constexpr size_t kMaxDrawNameBytes = kDrawNameField - 1;  // always NUL-terminated
inline constexpr uint32_t kMaxDraws = 1u << 20;

inline constexpr uint32_t kMaxFrameSize = 65535;  // x, y are u16

// CSV form: the most bytes a line may have before its '\n' (a CR included).
// Bounds the reader's memory whatever the file holds (FORMAT.md section 8).
inline constexpr size_t kMaxCsvLineBytes = 65536;

// header_bytes of a v1 file written by this library (readers accept any larger
// multiple of 64 and skip the extra bytes).
inline constexpr uint64_t headerBytesFor(uint64_t draw_count) {
  return kFixedHeaderBytes + draw_count * kDrawEntryBytes;
}

// Draw state table (version 2): 32 bytes per draw, right after the draw table.
inline constexpr size_t kDrawStateEntryBytes = 32;
inline constexpr size_t kStateOffBlend = 0;      // u8, BlendMode
inline constexpr size_t kStateOffDepth = 1;      // u8, bit 0 depth test, bit 1 depth write
inline constexpr size_t kStateOffDepthFunc = 2;  // u16, GL enum
inline constexpr size_t kStateOffBlendEnums = 4; // u16 x 6: eq, src, dst (RGB), eq, src, dst (alpha)
inline constexpr size_t kStateOffFragments = 16; // u64
inline constexpr size_t kStateOffReserved = 24;  // u8[8], zero
inline constexpr uint64_t drawStateTableOffset(uint64_t draw_count) {
  return kFixedHeaderBytes + draw_count * kDrawEntryBytes;
}
// header_bytes of a file of the given version written by this library.
inline constexpr uint64_t headerBytesFor(uint64_t draw_count, uint32_t version) {
  if (version < kVersion2) return headerBytesFor(draw_count);
  return (drawStateTableOffset(draw_count) + draw_count * kDrawStateEntryBytes + 63) / 64 * 64;
}

inline constexpr uint32_t kFp32RecordBytes = 32;
inline constexpr uint32_t kUnorm8RecordBytes = 20;

// 0 for an encoding value this version does not know.
inline constexpr uint32_t recordBytes(ColourEncoding e) {
  switch (e) {
    case ColourEncoding::Fp32: return kFp32RecordBytes;
    case ColourEncoding::Unorm8: return kUnorm8RecordBytes;
  }
  return 0;
}

// Record fields, in record order.
enum class Field : uint8_t { X, Y, Z, R, G, B, A, Prim, Draw };
inline constexpr size_t kFieldCount = 9;

inline constexpr const char* fieldName(Field f) {
  constexpr const char* names[kFieldCount] = {"x", "y", "z", "r", "g", "b", "a", "prim", "draw"};
  return names[static_cast<size_t>(f)];
}

// Byte offset of a field inside a record of the given encoding.
inline constexpr uint32_t fieldOffset(ColourEncoding e, Field f) {
  constexpr uint32_t fp32[kFieldCount] = {0, 2, 4, 8, 12, 16, 20, 24, 28};
  constexpr uint32_t unorm8[kFieldCount] = {0, 2, 4, 8, 9, 10, 11, 12, 16};
  return (e == ColourEncoding::Unorm8 ? unorm8 : fp32)[static_cast<size_t>(f)];
}

}  // namespace oit::format_v1
