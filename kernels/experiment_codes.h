/* The codes of the integrands (INTEGRAND, clsamp/integrands/base.py) and of the integrand
 * families (FAMILY, clsamp/families.py): what the fp64 kernels (integrand.h, families.cl)
 * and the float-float ones (experiments_ff.h) select their case by. */
#ifndef CLSAMP_EXPERIMENT_CODES_H
#define CLSAMP_EXPERIMENT_CODES_H

#define GAUSSIAN 0
#define DISK 1
#define HEAVISIDE 2
#define PMJ_DISK 3
#define PMJ_GAUSSIAN 4
#define PMJ_BILINEAR 5
#define PMJ_STEP 6
#define PMJ_TRIANGLE 7
#define GENZ_OSCILLATORY 8      /* Genz's six families (clsamp.integrands.Genz): */
#define GENZ_PRODUCT_PEAK 9     /* p = (a_0 .. a_{D-1}, u_0 .. u_{D-1}, 2 pi u_0) */
#define GENZ_CORNER_PEAK 10
#define GENZ_GAUSSIAN 11
#define GENZ_CONTINUOUS 12
#define GENZ_DISCONTINUOUS 13
#define KEISTER 14              /* p = (pi^(d/2), 1/sqrt(2)) */
#define USER_SOURCE 15          /* clsamp_user_integrand, after this file; p unused */

#define GAUSSIANS 0
#define HEAVISIDES 1
#define DISKS 2
#define BOXES 3
#define CLIPPED 4

#endif
