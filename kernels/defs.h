/* capdem device-safe definitions: compiled as C11 (host, OpenMP) and as
 * OpenCL C 1.2.  Everything a kernel header needs from the language lives
 * here: the real type, index types, vector structs and the macros that hide
 * address spaces and OpenMP declare-target regions. */
#ifndef CD_DEFS_H
#define CD_DEFS_H

/* cd_flag: a yes/no column of the step (0 or 1), one byte a row: a pair row's
 * contact flag (kernels/fields.def, pair_active), 3 B a row less than a
 * cd_int.  Every backend reads and writes it as a byte (OpenCL C 1.1 and
 * later store bytes to __global memory without an extension); the run
 * file keeps it as a 32-bit integer (h5type FLAG: HDF5 converts at write
 * and read, src/io/io_h5_layout.c).  docs/performance.md, "Session 19, a
 * byte a contact flag". */
#ifdef __OPENCL_VERSION__
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
/* Bitwise agreement with the host build (-ffp-contract=off). */
#pragma OPENCL FP_CONTRACT OFF
typedef double cd_real;
typedef int cd_int;
typedef uint cd_uint;
typedef long cd_long;
typedef ulong cd_ulong;
typedef uchar cd_flag;
#define CD_GLOBAL      __global
#define CD_CONST_TABLE __constant
#define CD_DEVICE_BEGIN
#define CD_DEVICE_END
#else
#include <math.h>
#include <stdint.h>
typedef double cd_real;
typedef int32_t cd_int;
typedef uint32_t cd_uint;
typedef int64_t cd_long;
typedef uint64_t cd_ulong;
typedef uint8_t cd_flag;
#define CD_GLOBAL
#define CD_CONST_TABLE static const
#if defined(_OPENMP)
/* Functions between these markers are compiled for the offload target too. */
#define CD_DEVICE_BEGIN _Pragma("omp declare target")
#define CD_DEVICE_END   _Pragma("omp end declare target")
#else
#define CD_DEVICE_BEGIN
#define CD_DEVICE_END
#endif
#endif

#define CD_INLINE static inline
/* A pointer parameter the function neither keeps nor hands on.  Clang's
 * OpenMP offload otherwise keeps every local whose address reaches a
 * call that is not inlined yet in device heap memory ("globalization",
 * remark OMP113): on the H100 the neighbour build's kernels that passed a
 * local grid by address ran 50-400 times slower than their arithmetic
 * (docs/performance.md, "First GPU runs").  Only Clang knows it; OpenCL C
 * has no globalization. */
#if defined(__clang__) && !defined(__OPENCL_VERSION__)
#define CD_NOESCAPE __attribute__((noescape))
#else
#define CD_NOESCAPE
#endif
/* A pointer type declared `typedef T *name CD_ALIGN_VALUE(T)` tells Clang
 * what C already guarantees, that it points at a T aligned as T.  Without
 * it a T passed by value from memory reached through a loaded pointer (a
 * column element: cd_v3_sub(c.position[q], x)) is copied, when the callee
 * is inlined, by a memcpy of unknown source alignment (LLVM's inliner
 * writes align 1 for a byval argument and leaves the rest to alignment
 * inference, which knows nothing of a pointer loaded from memory).  x86-64
 * loads unaligned words, but NVPTX splits such a copy into byte loads: the
 * omp offload step's pair kernel read a hexapod's vectors as 1,016 byte
 * loads (docs/performance.md, "The omp offload kernels on sm_90, read from
 * the compiler").  Clang only; OpenCL C copies byval arguments from
 * __global memory with the type's alignment, and GCC has no such attribute. */
#if defined(__clang__) && !defined(__OPENCL_VERSION__)
#define CD_ALIGN_VALUE(T) __attribute__((align_value(_Alignof(T))))
#else
#define CD_ALIGN_VALUE(T)
#endif
/* An item that must be inlined on an NVIDIA GPU: Clang 16's inliner
 * leaves a large function with two callers in one file a call
 * (cd_advance_from, cd_nb_item_collect), and a call passes its cd_cols by
 * value (528 B) and every local whose address it takes through the
 * thread's stack in local memory (docs/performance.md, "The omp offload
 * kernels on sm_90, read from the compiler").  Elsewhere (host, OpenCL) a
 * plain inline function. */
#if defined(__NVPTX__) && !defined(__OPENCL_VERSION__)
#define CD_INLINE_ALWAYS static inline __attribute__((always_inline))
#else
#define CD_INLINE_ALWAYS static inline
#endif
#define CD_R(x) ((cd_real)(x))
#define CD_PI   CD_R(3.14159265358979323846)

/* Named index types: what an integer indexes is part of its type name. */
typedef cd_int cd_particle_id; /* index into particle columns */
typedef cd_int cd_prim_id;     /* index into primitive (arm) columns */
typedef cd_int cd_pair_id;     /* index into pair/contact columns */
typedef cd_int cd_shape_id;    /* index into the shape catalogue */

/* Integer atomic increment, returning the old value: counting sorts only
 * (kernels/neighbor_items.h), never a floating-point sum.  OpenMP's atomic
 * is atomic among all threads of the device (teams included); without
 * OpenMP the code runs on one thread and it is a plain increment. */
#ifdef __OPENCL_VERSION__
#define cd_atomic_inc(p) atomic_inc(p)
#else
#if defined(_OPENMP)
#pragma omp declare target
#endif
static inline cd_int cd_atomic_inc(cd_int *p)
{
    cd_int old;
#if defined(_OPENMP)
#pragma omp atomic capture
#endif
    old = (*p)++;
    return old;
}
#if defined(_OPENMP)
#pragma omp end declare target
#endif
#endif

/* Own vector structs: OpenCL's double3 is 32 bytes and differs from C. */
typedef struct {
    cd_real x, y, z;
} cd_vec3;
typedef struct {
    cd_real w, x, y, z;
} cd_quat; /* unit quaternion, w scalar */

#endif
