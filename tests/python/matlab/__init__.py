"""End-to-end tests of the MATLAB/GNU Octave client (matlab/, docs/matlab.md) against a real manager."""
