//! Holzschuch–Pacanowski two-scale BRDF (work in progress, not yet exported).
