"""Column layout of the packed parameter, state and output arrays of the compiled kernels.

The kernels take one float64 row per actuator. Index constants are module globals, which
numba folds into the compiled code as literals.
"""

# --- parameters ------------------------------------------------------------------------
P_K = 0  # heat capacity ratio [-]
P_R = 1  # gas constant [J/(kg K)]
P_CP = 2  # specific heat cp [J/(kg K)]
P_TS = 3  # supply temperature [K]
P_PATM = 4  # atmospheric pressure [Pa]
P_CRITICAL = 5  # critical pressure ratio [-]
P_C1 = 6  # unchoked flow constant (eq 4.1.8)
P_C2 = 7  # choked flow constant (eq 4.1.9)
P_PS = 8  # regulated supply pressure [Pa]
P_PE = 9  # exhaust pressure [Pa]
P_CAP_AREA = 10  # [m^2]
P_ROD_AREA = 11  # [m^2]
P_ROD_SECTION = 12  # [m^2]
P_STROKE = 13  # [m]
P_CAP_DEAD = 14  # [m]
P_ROD_DEAD = 15  # [m]
P_BORE = 16  # [m]
P_VALVE_MODEL = 17  # VALVE_SIMPLE / VALVE_UNDERLAPPED
P_FLOW_FORM = 18  # FLOW_ORIFICE / FLOW_ISO6358
P_OFFSET = 19  # [V]
P_UMIN = 20  # [V]
P_UMAX = 21  # [V]
P_SPOOL_TAU = 22  # [s], 0 = no lag
P_LAMINAR = 23  # [-]
P_SIMPLE_MAX_AREA = 24  # [m^2]
P_SIMPLE_LEAK_AREA = 25  # [m^2]
P_SIMPLE_FULL_SCALE = 26  # [V]
P_CD_CAP = 27  # [-]
P_CD_ROD = 28  # [-]
P_ISO_CONDUCTANCE = 29  # [m^3/(s Pa)]
P_ISO_LEAK_CONDUCTANCE = 30  # [m^3/(s Pa)]
P_ISO_B = 31  # [-]
P_CAP_POLY_NEG = 32  # 5 coefficients [m^2/V^n], highest power first
P_CAP_POLY_POS = 37
P_ROD_POLY_NEG = 42
P_ROD_POLY_POS = 47
P_CAP_HIGH_CUTOFF = 52  # [V]
P_CAP_LOW_CUTOFF = 53
P_ROD_HIGH_CUTOFF = 54
P_ROD_LOW_CUTOFF = 55
P_FRICTION_MODEL = 56
P_FS = 57  # [N]
P_FC = 58  # [N]
P_CV = 59  # [N s/m]
P_VS = 60  # [m/s]
P_EXPONENT = 61  # [-]
P_KTANH = 62  # [s/m]
P_DAMPING = 63  # [N s/m]
P_SIGMA0 = 64  # [N/m]
P_SIGMA1 = 65  # [N s/m]
P_THERMO_MODEL = 66
P_POLYTROPIC_N = 67  # [-]
P_HEAT_TRANSFER = 68  # [W/(m^2 K)]
P_WALL_TEMPERATURE = 69  # [K]
P_PISTON_MASS = 70  # [kg]
# single-DoF rig (ignored by the externally driven kernel)
P_MOVING_MASS = 71  # load + piston [kg]
P_GRAVITY_FORCE = 72  # weight along +x [N]
P_STOP_STIFFNESS = 73  # [N/m]
P_STOP_DAMPING = 74  # [N s/m]
P_SPACER = 75  # 1.0 = piston fixed at full extension
# underlapped valve sub-models (thesis 5.5.3 Table 3: the valve's two parts separately)
P_AREA_CURVE = 76  # AREA_POLYNOMIAL / AREA_LINEAR
P_INPUT_PRESSURE = 77  # INPUT_TANH / INPUT_SWITCHED
N_PARAMETERS = 78

VALVE_SIMPLE = 0
VALVE_UNDERLAPPED = 1
FLOW_ORIFICE = 0
FLOW_ISO6358 = 1
AREA_POLYNOMIAL = 0
AREA_LINEAR = 1
INPUT_TANH = 0
INPUT_SWITCHED = 1

# --- state -----------------------------------------------------------------------------
S_CAP_PRESSURE = 0  # [Pa]
S_ROD_PRESSURE = 1  # [Pa]
S_CAP_MASS = 2  # [kg]
S_ROD_MASS = 3  # [kg]
S_SPOOL = 4  # effective centered voltage after the spool lag [V]
S_BRISTLE = 5  # LuGre bristle deflection [m]
S_AIR_CONSUMED = 6  # mass drawn from the supply since the start [kg]
S_POSITION = 7  # piston extension [m] (rig only; the robot kernel gets it as input)
S_VELOCITY = 8  # [m/s]
N_STATES = 9

# --- per-step outputs ------------------------------------------------------------------
O_CAP_FLOW = 0  # mean net mass flow into the cap chamber over the step [kg/s]
O_ROD_FLOW = 1  # mean net mass flow into the rod chamber over the step [kg/s]
O_PNEUMATIC_FORCE = 2  # eq 4.1.11 without friction, end of step [N]
O_FRICTION_FORCE = 3  # [N]
O_END_STOP_FORCE = 4  # [N]
O_CAP_TEMPERATURE = 5  # [K]
O_ROD_TEMPERATURE = 6  # [K]
O_SUPPLY_DRAW = 7  # mean mass flow drawn from the supply [kg/s]
N_OUTPUTS = 8

# --- shared supply ---------------------------------------------------------------------
SUPPLY_MODEL = 0  # 0 ideal, 1 tank
SUPPLY_TANK_PRESSURE = 1  # [Pa]
SUPPLY_TANK_VOLUME = 2  # [m^3]
SUPPLY_TANK_TEMPERATURE = 3  # [K]
SUPPLY_DRAWN_MASS = 4  # total mass drawn from the supply [kg]
SUPPLY_GAS_CONSTANT = 5  # R of the stored gas [J/(kg K)]
N_SUPPLY = 6
