"""
Applications
============

Clients of the measuring API and the engine that answer a user's question in the user's
own units (derived quantities, fitted parameters, renderer tables): each one subpackage,
with no sizing, checkpoint or file-writing code of its own.
"""
