/* FFT order: sample i of an n-sample axis lies at the signed index i (i <= (n-1)/2) or i - n. */
#ifndef HOLO_FFT_ORDER_H
#define HOLO_FFT_ORDER_H

inline int signed_index(int i, int n) { return i <= (n - 1) / 2 ? i : i - n; }

#endif
