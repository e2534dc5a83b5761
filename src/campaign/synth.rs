//! Synthesis of the paper's test program (R1-R3, S1-S9, T1-T6).
