/* The kernels' `real`, for the coordinates and phases that must be formed exactly: double
 * where the runtime builds with -DHOLO_FP64 (Runtime.real_options: the device has float64),
 * float elsewhere. The host passes such arguments as Runtime.real (opencl/kernel.py's REAL). */
#ifndef HOLO_REAL_H
#define HOLO_REAL_H

#ifdef HOLO_FP64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
typedef double real;
#else
typedef float real;
#endif

#endif
