/* csjm_qp.h: the bounded tension QP of csjm.h (internal). */
#ifndef CSJM_QP_H
#define CSJM_QP_H

#include "csjm.h"

#define CSJM_QP_OK 0
#define CSJM_QP_NOT_SETTLED 1

/* Primal-dual active set (Hintermueller, Ito & Kunisch 2002) on
 *     min 1/2 |t - t_ref|^2,  J^T t = b,  lo <= t <= hi
 * from the active sets lower/upper (updated in place), at most max_iter iterations. */
int csjm_qp_pdas(const double J[3 * CSJM_N_CABLES], const double b[3], const double t_ref[CSJM_N_CABLES], double lo, double hi,
                 unsigned char lower[CSJM_N_CABLES], unsigned char upper[CSJM_N_CABLES], int max_iter, double t[CSJM_N_CABLES], int *iterations);

/* Exhaustive search of the 3^m bound patterns (those with at least three free cables) for the KKT point. */
int csjm_qp_exhaustive(const double J[3 * CSJM_N_CABLES], const double b[3], const double t_ref[CSJM_N_CABLES], double lo, double hi,
                       unsigned char lower[CSJM_N_CABLES], unsigned char upper[CSJM_N_CABLES], double t[CSJM_N_CABLES]);

/* Largest signed distance (>0: outside) of b from the facet planes of the zonotope
 * {J^T t : lo <= t <= hi} (m (m - 1) facet normals); <= 0 means b lies in it. */
double csjm_qp_outside_margin(const double J[3 * CSJM_N_CABLES], const double b[3], double lo, double hi);

/* min |J^T t - b| over lo <= t <= hi for b outside the zonotope (exact: the nearest point has
 * at most two free cables; m (m - 1) / 2 pairs x 2^(m - 2) corner assignments); t receives a minimiser. */
double csjm_qp_distance(const double J[3 * CSJM_N_CABLES], const double b[3], double lo, double hi, double t[CSJM_N_CABLES]);

#endif /* CSJM_QP_H */
