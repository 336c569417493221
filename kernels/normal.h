/* The standard normal quantile: Wichura's AS 241 (PPND16), the OpenCL twin of
 * clsamp.transforms.to_normal, Horner's rule in its order (build with FP_CONTRACT OFF;
 * the device's log decides the last bits in the tails). u = 0 is taken as 2^-1022.
 * clsamp_to_normal (double) and clsamp_to_normal4 (double4). */
#ifndef CLSAMP_NORMAL_H
#define CLSAMP_NORMAL_H

#define CLSAMP_HORNER8(x, c0, c1, c2, c3, c4, c5, c6, c7) \
    ((((((((c0) * (x) + (c1)) * (x) + (c2)) * (x) + (c3)) * (x) + (c4)) * (x) + (c5)) * (x) + (c6)) * (x) + (c7))

/* One definition for double and double4 (T), without branches between lanes: every lane
 * evaluates the central rational function and, unless every lane is central (ALL: the
 * test over the lanes), the tail's, then selects (as clsamp.transforms.to_normal does with
 * np.where), so four lanes run in SIMD. Each lane's operations are the scalar algorithm's,
 * in its order. */
#define CLSAMP_TO_NORMAL(name, T, ALL)                                                         \
    inline T name(const T u)                                                                   \
    {                                                                                          \
        const T p = u > 0x1p-1022 ? u : (T)(0x1p-1022);                                        \
        const T q = p - 0.5;                                                                   \
        const T r = 0.180625 - q * q;                                                          \
        const T middle = q * CLSAMP_HORNER8(r, 2.5090809287301226727e+3, 3.3430575583588128105e+4, \
                                            6.7265770927008700853e+4, 4.5921953931549871457e+4, \
                                            1.3731693765509461125e+4, 1.9715909503065514427e+3, \
                                            1.3314166789178437745e+2, 3.3871328727963666080e+0) \
            / CLSAMP_HORNER8(r, 5.2264952788528545610e+3, 2.8729085735721942674e+4,             \
                             3.9307895800092710610e+4, 2.1213794301586595867e+4,                \
                             5.3941960214247511077e+3, 6.8718700749205790830e+2,                \
                             4.2313330701600911252e+1, 1.0);                                    \
        if (ALL(fabs(q) <= 0.425))                                                             \
            return middle;                                                                     \
        const T tail = sqrt(-log(q < 0.0 ? p : 1.0 - p));                                      \
        const T t_near = tail - 1.6, t_far = tail - 5.0;                                       \
        const T near = CLSAMP_HORNER8(t_near, 7.74545014278341407640e-4, 2.27238449892691845833e-2, \
                                      2.41780725177450611770e-1, 1.27045825245236838258e+0,    \
                                      3.64784832476320460504e+0, 5.76949722146069140550e+0,    \
                                      4.63033784615654529590e+0, 1.42343711074968357734e+0)    \
            / CLSAMP_HORNER8(t_near, 1.05075007164441684324e-9, 5.47593808499534494600e-4,      \
                             1.51986665636164571966e-2, 1.48103976427480074590e-1,              \
                             6.89767334985100004550e-1, 1.67638483018380384940e+0,              \
                             2.05319162663775882187e+0, 1.0);                                   \
        const T far = CLSAMP_HORNER8(t_far, 2.01033439929228813265e-7, 2.71155556874348757815e-5, \
                                     1.24266094738807843860e-3, 2.65321895265761230930e-2,     \
                                     2.96560571828504891230e-1, 1.78482653991729133580e+0,     \
                                     5.46378491116411436990e+0, 6.65790464350110377720e+0)     \
            / CLSAMP_HORNER8(t_far, 2.04426310338993978564e-15, 1.42151175831644588870e-7,      \
                             1.84631831751005468180e-5, 7.86869131145613259100e-4,              \
                             1.48753612908506148525e-2, 1.36929880922735805310e-1,              \
                             5.99832206555887937690e-1, 1.0);                                   \
        const T value = tail <= 5.0 ? near : far;                                              \
        return fabs(q) <= 0.425 ? middle : (q < 0.0 ? -value : value);                         \
    }

#define CLSAMP_ALL_SCALAR(x) (x)
CLSAMP_TO_NORMAL(clsamp_to_normal, double, CLSAMP_ALL_SCALAR)
CLSAMP_TO_NORMAL(clsamp_to_normal4, double4, all)

#endif
