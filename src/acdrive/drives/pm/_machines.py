"""The PM drive's machines: the published permanent-magnet machines and their ratings are a
catalog of the machines layer (``acdrive.machines._pm_catalog``, with the source of every
number), so that identification benches and other layers below the drives read them too."""

from acdrive.machines._pm_catalog import (  # noqa: F401
    BLY171D,
    BLY171D_B,
    BLY171D_I_RATED_PEAK,
    BLY171D_KE,
    BLY171D_N_MAX,
    BLY171D_T_RATED,
    BLY171D_V_DC,
    IPMSM_2KW2,
    IPMSM_2KW2_F_NOM,
    IPMSM_2KW2_I_NOM,
    IPMSM_2KW2_P_NOM,
    IPMSM_2KW2_T_NOM,
    IPMSM_2KW2_U_NOM,
    IPMSM_2KW2_V_DC,
)
