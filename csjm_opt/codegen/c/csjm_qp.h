/* csjm_qp.h: the bounded tension QP of csjm.h (internal). */
#ifndef CSJM_QP_H
#define CSJM_QP_H

#define CSJM_QP_OK 0
#define CSJM_QP_NOT_SETTLED 1

/* Primal-dual active set (Hintermueller, Ito & Kunisch 2002) on
 *     min 1/2 |t - t_ref|^2,  J^T t = b,  lo <= t <= hi
 * from the active sets lower/upper (updated in place), at most max_iter iterations. */
int csjm_qp_pdas(const double J[18], const double b[3], const double t_ref[6], double lo, double hi,
                 unsigned char lower[6], unsigned char upper[6], int max_iter, double t[6], int *iterations);

/* Exhaustive search of the 233 active sets with at least three free cables for the KKT point. */
int csjm_qp_exhaustive(const double J[18], const double b[3], const double t_ref[6], double lo, double hi,
                       unsigned char lower[6], unsigned char upper[6], double t[6]);

/* Largest signed distance (>0: outside) of b from the facet planes of the zonotope
 * {J^T t : lo <= t <= hi} (30 facet normals); <= 0 means b lies in it. */
double csjm_qp_outside_margin(const double J[18], const double b[3], double lo, double hi);

/* min |J^T t - b| over lo <= t <= hi for b outside the zonotope (exact: the nearest point has
 * at most two free cables; 15 pairs x 16 corner assignments); t receives a minimiser. */
double csjm_qp_distance(const double J[18], const double b[3], double lo, double hi, double t[6]);

#endif /* CSJM_QP_H */
