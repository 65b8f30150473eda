/* The slices and incident directions of the tests against the adding-doubling reference
 * (test_media_stacks, test_band_blocks), and the reference's grid that holds them
 * exactly: theta_o 0, 60 and 85 degrees; theta_i 0, 40, 70, 80, 87 and 89 degrees at
 * azimuths 0, 90 and 180 from wo's (one direction at 0), upwards then downwards.
 * Include after ref_adding.h. */
#ifndef LSQT_TEST_STACK_DIRS_H
#define LSQT_TEST_STACK_DIRS_H

enum { NTH = 6, NWI = 1 + 3 * (NTH - 1), NWI_T = 2 * NWI, NS = 3 };
static const double TH_I[NTH] = {0, 40, 70, 80, 87, 89}, PH_I[3] = {0, 90, 180};
static const double DEG_O[NS] = {0, 60, 85};

/* The directions (up, then down), as the state keeps them (float), and the (side,
 * theta_i) group of each in grp[]. */
static void stack_dirs(double (*d)[3], int *grp)
{
    int n = 0;
    for (int side = 0; side < 2; side++)
        for (int t = 0; t < NTH; t++)
            for (int p = 0; p < (t ? 3 : 1); p++, n++) {
                const double th = TH_I[t] * PI / 180.0, ph = PH_I[p] * PI / 180.0;
                d[n][0] = (float)(sin(th) * cos(ph)), d[n][1] = (float)(sin(th) * sin(ph));
                d[n][2] = (float)(side ? -cos(th) : cos(th));
                grp[n] = side * NTH + t;
            }
}

/* The reference's grid: the quadrature, then the directions' |z| and the slices' cosines. */
static void stack_grid(ad_grid *G, int per_panel, int modes)
{
    double d[NWI_T][3], extra[NTH + NS];
    int grp[NWI_T], n = 0;
    stack_dirs(d, grp);
    for (int k = 0; k < NWI; k++)
        if (k == 0 || fabs(d[k][2]) != extra[n - 1]) extra[n++] = fabs(d[k][2]);
    for (int s = 0; s < NS; s++) extra[n++] = cos(DEG_O[s] * PI / 180.0);
    ad_grid_init(G, per_panel, modes, extra, n);
}

#endif
