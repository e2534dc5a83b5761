//! Spectral estimates: Welch-averaged H1, H2 and coherence (realfft).
