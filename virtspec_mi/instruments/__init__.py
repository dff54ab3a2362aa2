"""
Instruments
===========

The instruments that measure a specimen through the engine.
"""
