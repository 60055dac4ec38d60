"""Which NASTRAN bulk-data entries and PARAMs :func:`trussid.fem.nastran.read_bdf` translates, accepts
without effect on the modes, or refuses."""

from __future__ import annotations




__all__ = ['SUPPORTED_CARDS', 'RAW_CARDS', 'IGNORED_CARDS', 'NOTED_CARDS', 'CASE_SELECTED_CARDS',
           'THERMAL_CARDS', 'HANDLED_PARAMS', 'MODE_PARAMS', 'OUTPUT_PARAMS', 'SECTION_TYPES']


#: Bulk-data cards :func:`read_bdf` translates.
SUPPORTED_CARDS = frozenset({
    "GRID", "GRDSET", "CORD1R", "CORD2R", "CORD1C", "CORD2C", "CORD1S", "CORD2S",
    "CBAR", "CBEAM", "CROD", "CONROD", "PBAR", "PBARL", "PBEAM", "PBEAML", "PROD", "PTUBE",
    "MAT1", "CONM2", "CMASS1", "CMASS2", "PMASS", "CELAS1", "CELAS2", "PELAS", "CBUSH", "PBUSH",
    "RBE2", "RBE3", "RBAR", "MPC", "MPCADD", "CRIGD1", "CRIGD2", "CRIGD3", "CRIGDR",
    "SPC", "SPC1", "SPCADD", "OMIT", "OMIT1", "ASET", "ASET1", "SUPORT", "SUPORT1", "SPOINT",
    "BSET", "BSET1", "QSET", "QSET1", "BAROR", "BEAMOR", "CONM1", "GENEL",
    "CELAS3", "CELAS4", "CMASS3", "CMASS4", "DMIG",
    "EIGRL", "EIGR", "PARAM", "ENDDATA",
})


#: Entries the reader takes from their fields directly (NASTRAN-95 rigid elements, CONM1,
#: GENEL, scalar-point elements, DMIG), not through :mod:`trussid.fem.nastran.bulk`.
RAW_CARDS = frozenset({"CRIGD1", "CRIGD2", "CRIGD3", "CRIGDR", "CONM1", "GENEL",
                       "CELAS3", "CELAS4", "CMASS3", "CMASS4", "DMIG"})

#: Entries that cannot change the real eigenvalues of the structure: accepted, not
#: translated, and listed with their counts in :attr:`BdfInfo.ignored`. Loads and enforced
#: motion (a SOL 103 run has no load; SPCD values are irrelevant to modes, their SPC set is
#: read), dynamic-load, frequency and random tables, damping (real modes are undamped),
#: aeroelastic model (its splines only read the structural modes), output and DMAP book-
#: keeping (USET, DTI, MDLPRM, PLOTEL), thermal materials (MAT4/MAT5: heat transfer only)
#: and the complex-eigenvalue method EIGC.
IGNORED_CARDS = frozenset({
    # static and dynamic loads, enforced motion
    "FORCE", "FORCE1", "FORCE2", "MOMENT", "MOMENT1", "MOMENT2", "LOAD", "GRAV", "ACCEL",
    "ACCEL1", "PLOAD", "PLOAD1", "PLOAD2", "PLOAD4", "RFORCE", "SPCD", "DLOAD", "RLOAD1",
    "RLOAD2", "TLOAD1", "TLOAD2", "DAREA", "DELAY", "DPHASE", "LSEQ", "ACSRCE",
    # tables, frequencies, random and transient set-up
    "TABLED1", "TABLED2", "TABLED3", "TABLED4", "TABDMP1", "TABRND1", "TABRNDG", "RANDPS",
    "RANDT1", "FREQ", "FREQ1", "FREQ2", "FREQ3", "FREQ4", "FREQ5", "TSTEP", "TSTEP1", "NLPARM",
    "EIGC",
    # damping elements (real modes are undamped)
    "CDAMP1", "CDAMP2", "CDAMP3", "CDAMP4", "CVISC", "PDAMP", "PVISC",
    # aeroelastic model
    "AERO", "AEROS", "CAERO1", "CAERO2", "CAERO3", "CAERO4", "CAERO5", "PAERO1", "PAERO2",
    "PAERO3", "PAERO4", "PAERO5", "SPLINE1", "SPLINE2", "SPLINE3", "SPLINE4", "SPLINE5", "SET1",
    "SET2", "AEFACT", "AELIST", "AESTAT", "AESURF", "AESURFS", "AELINK", "AEPARM", "AECOMP",
    "AECOMPL", "MKAERO1", "MKAERO2", "FLFACT", "FLUTTER", "GUST", "TRIM", "DIVERG", "MONPNT1",
    "MONPNT2", "MONPNT3", "MONDSP1", "CSSCHD", "AEDW", "AEPRESS", "AEFORCE",
    # output, sets for DMAP, tables for post-processing, plotting
    "MDLPRM", "USET", "USET1", "DTI", "PLOTEL",
    # MYSTRAN's output and debug switches
    "DEBUG", "PARVEC", "PARVEC1",
    # heat-transfer materials (structural SOL 103 does not use them)
    "MAT4", "MAT5",
})


#: Entries accepted with a note (in :attr:`BdfInfo.notes`, and listed in
#: :attr:`BdfInfo.ignored`) saying why they cannot change the real modes (issue 33): the
#: reason is printed with the entry's name. Those in :data:`CASE_SELECTED_CARDS` are refused
#: instead when the case control selects them.
NOTED_CARDS = {
    "EIGP": "poles for the complex eigenvalue search (CMETHOD), not used by real modes",
    "SEQGP": "grid point resequencing: the order of the equations, not the structure",
    "SEQEP": "extra point resequencing: the order of the equations, not the structure",
    "EPOINT": "extra points belong to dynamic response (transfer functions), not to real modes",
    "TF": "transfer function not selected by TFL in the case control",
    **dict.fromkeys(("ROTORD", "ROTORG", "ROTORB", "RSPINR", "RSPINT", "UNBALNC"),
                    "rotordynamics without RGYRO in the case control: the real modes are the structure's at rest"),
}

#: Noted entries that count when the case control selects them, with the selecting request:
#: then refused, naming the entry. Rotordynamics (RGYRO) adds gyroscopic and spin-softening
#: terms, and TFL adds transfer functions to the equations of motion; trussid computes neither.
CASE_SELECTED_CARDS = {
    **dict.fromkeys(("ROTORD", "ROTORG", "ROTORB", "RSPINR", "RSPINT", "UNBALNC"), "RGYRO"),
    "TF": "TFL",
}

#: Temperature-dependent material entries: ignored like the above unless the deck gives
#: temperatures (TEMP/TEMPD), when they would change the stiffness and are refused.
THERMAL_CARDS = frozenset({"MATT1", "TABLEM1", "TABLEM2", "TABLEM3", "TABLEM4", "TEMPD", "TEMP"})

#: PARAMs read. Every other PARAM is accepted and listed in :attr:`BdfInfo.ignored`
#: unless it is one of :data:`MODE_PARAMS`: NASTRAN has hundreds of PARAMs (and MYSTRAN,
#: NASTRAN-95 their own), and those that change a beam model's real modes are few.
HANDLED_PARAMS = frozenset({"WTMASS", "COUPMASS", "AUTOSPC"})

#: PARAMs that change the real modes and are not translated: the scale factors of direct
#: input matrices (K2GG, M2GG... through CK1-CK3, CM1-CM2, CP1-CP2, CB1-CB2). Refused unless
#: they keep their default 1.0.
MODE_PARAMS = frozenset({"CK1", "CK2", "CK3", "CM1", "CM2", "CP1", "CP2", "CB1", "CB2"})

#: PARAMs known to have no effect on the real modes of a beam model (output and solver
#: book-keeping, damping, aeroelastic and shell-only settings): listed like any other
#: accepted PARAM; kept as the documented list of those checked.
OUTPUT_PARAMS = frozenset({
    "POST", "PRTMAXIM", "GRDPNT", "OGEOM", "NOCOMPS", "PATVER", "SRCOMPS", "EST", "OUGCORD",
    "MAXRATIO", "BAILOUT", "NEWSEQ", "LMODES", "RESVEC", "PRGPST", "SEMAPPRT", "USETPRT",
    "AUTOMSET", "DDRMM", "POSTEXT", "PRINT", "NASPRT", "SOLADJC", "G", "W3", "W4", "K6ROT",
    "SNORM", "LAMLIM", "OIBULK", "OMACHPR", "RDRBE", "RSCON", "RSOPT", "UNITSYS", "KDAMP",
    "OPPHIPA", "GUSTAERO", "AUNITS", "Q", "USETSEL", "GRDEQ", "RPOSTS1", "SPARSEDR", "LGDISP",
    "MACH", "VREF", "OPGTKG", "PRTPCH", "DBALL", "SCRSAVE", "DBDICT", "DBUP", "OUNIT1", "OUNIT2",
    "SEP1XOVR", "AUTOQSET", "CHECKOUT", "OPTEXIT", "INREL", "FIXEDB", "MODACC", "NOELOF",
    "NOELOP", "NOGPF", "NOPRT", "PRTGPL", "PRTEQXIN", "PRTGPDT", "PRTCSTM", "PRTBGPDT",
    "PRTGPTT", "PRTMGG", "PRTPG", "ERROR", "DBCDIAG", "TINY", "XFLAG",
})


#: PBARL/PBEAML shapes with a matching :class:`trussid.fem.sections.Section` constructor.
SECTION_TYPES = ("ROD", "TUBE", "BAR", "BOX")
