/* Writes pbrt_band_names.txt: the EXR channel names pbrt-v4's SpectralFilm
 * gives its buckets over [360, 830] nm (src/pbrt/film.cpp, GetImage: the
 * bucket centre Lerp((i + 0.5f) / nBuckets, lambdaMin, lambdaMax) in f32,
 * Lerp(x, a, b) = (1 - x) * a + x * b, printed with "%.3f" and '.' replaced
 * by ','), so that tests/spectral_film.rs can check lustre's names without
 * pbrt. Written for this test from that description, not copied.
 * Build and run: cc -O0 -ffp-contract=off pbrt_band_names.c && ./a.out > pbrt_band_names.txt */
#include <stdio.h>
#include <string.h>

int main(void) {
    const int counts[] = {1, 2, 3, 7, 16, 31, 47, 64, 100, 255, 256};
    const float lo = 360.0f, hi = 830.0f;
    for (size_t k = 0; k < sizeof counts / sizeof counts[0]; k++) {
        int n = counts[k];
        for (int i = 0; i < n; i++) {
            float t = (i + 0.5f) / n;
            float centre = (1 - t) * lo + t * hi;
            char s[64];
            snprintf(s, sizeof s, "%.3fnm", centre);
            for (char *c = s; *c; c++)
                if (*c == '.') *c = ',';
            printf("%d %d S0.%s\n", n, i, s);
        }
    }
    return 0;
}
