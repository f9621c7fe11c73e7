"""Transfer functions: pure functions of 2-D focal-plane frequency (cy/mm) returning the OTF.

One module per physical stage (optics, detector, motion, atmosphere); ``budget`` multiplies the named
components of an :class:`~satchain.config.system.ImagingSystem` and takes cuts, MTF at Nyquist and MTFA;
``fitting`` estimates unknown system parameters from a measured MTF curve.

OTFs are returned signed/complex (a sinc changes sign past its first zero, which matters when an
image is simulated); the MTF is their modulus.
"""
