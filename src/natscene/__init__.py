"""natscene: render natural outdoor scenes from Dobashi 2012, Reimschuessel 2011 and Dong 2007.

Importing the package makes sure Dr.Jit will find a libLLVM it can load (see :mod:`natscene.llvm`)
before anything imports ``drjit`` or ``mitsuba``; nothing else happens at import time.
"""
from natscene import llvm as _llvm

__version__ = "0.1.0"

_llvm.configure()
