/* Certified directional-albedo table made by virtspec-mi (a virtual spectrophotometer).
 *   model:        virtspec-mi microfacet reflector (sampling consistent with eval): E = reflected, distribution ggx
 *   G and F:      ggx microfacet reflector, separable Smith G2 = G1(wi) G1(wo) (Walter et al. 2007, eq. 23), exact Smith G1, F = 1; the instrument counts the integral of f cos (virtspec-mi plugin 'microfacet': visible normals sampled with the exact Smith normalisation, weight G2 F / G1_exact(wi))
 *   measured:     Mitsuba 3.9.1 (llvm_ad_spectral), virtspec-mi 0.1.0, 2026-11-28T15:01:19+00:00
 *   grid:         engine convention 'grid'; memory order mu alpha (last index fastest)
 *   certificate:  every value (E and E_avg; 6 cells) within 0.1 of the model's true value at once with probability >= 0.99 (bound two-stage: delta/10 over the 6 pilots, 9 delta/10 over the second batches by pilot variance; union bound)
 *   epsilon = 0.1, delta = 0.01, bound = two-stage, rays = 3,895, seed = 5
 *   E = (reflected + transmitted rays) / rays of a collimated beam at theta_i = acos(mu);
 *   Eavg = the same under a cosine-weighted diffuse beam (2 * integral of E(mu) mu dmu, no quadrature).
 */
#ifndef VIRTSPEC_TABLE_GGX_GRID_ALBEDO_H
#define VIRTSPEC_TABLE_GGX_GRID_ALBEDO_H

#define TABLE_GGX_EPSILON 0.1
#define TABLE_GGX_DELTA 0.01
#define TABLE_GGX_RAYS 3895ULL

/* table_ggx_E: mu 2 x alpha 2 */
#define TABLE_GGX_E_SIZE 4
#define TABLE_GGX_E_EPSILON 0.1
static const float table_ggx_E[4] = {
  0.901098907f, 0.442857146f,
  0.813229561f, 0.489285707f
};

/* table_ggx_Eavg: alpha 2 */
#define TABLE_GGX_EAVG_SIZE 2
#define TABLE_GGX_EAVG_EPSILON 0.1
static const float table_ggx_Eavg[2] = {
  0.847222209f, 0.467857152f
};

#endif /* VIRTSPEC_TABLE_GGX_GRID_ALBEDO_H */
