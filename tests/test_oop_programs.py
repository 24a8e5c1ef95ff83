"""Realistic object-oriented ST programs as CODESYS and TwinCAT engineers write them (a state machine
framework, a command queue, an event bus, an axis simulation, a recipe manager, ST unit tests of an
OOP block), checked value by value against results worked out by hand."""

from st import PLC
from st.api import compile_text
from st.testing import TestSuite


def run(src: str, scans: int, dialect: str = "codesys") -> PLC:
    plc = PLC(compile_text(src, "programs.st", dialect=dialect))
    plc.scan(scans)
    return plc


STATE_MACHINE = """
{attribute 'qualified_only'}
TYPE E_State :
(
    IDLE := 0,
    STARTING := 1,
    RUNNING := 2,
    STOPPING := 3
);
END_TYPE

TYPE ST_Context :
STRUCT
    bStart   : BOOL;
    bStop    : BOOL;
    nTarget  : INT := 3;
    nProduced : INT;
    nCycles  : INT;
END_STRUCT
END_TYPE

INTERFACE I_State
METHOD Enter
END_METHOD
METHOD Execute : E_State
VAR_IN_OUT
    ctx : ST_Context;
END_VAR
END_METHOD
METHOD Leave
END_METHOD
PROPERTY Id : E_State
END_PROPERTY
END_INTERFACE

FUNCTION_BLOCK ABSTRACT FB_StateBase IMPLEMENTS I_State
VAR
    eId : E_State;
    nEnter : INT;
    nExec : INT;
    nLeave : INT;
END_VAR
END_FUNCTION_BLOCK

METHOD FB_init : BOOL
VAR_INPUT
    bInitRetains : BOOL;
    bInCopyCode : BOOL;
    eMyId : E_State;
END_VAR
eId := eMyId;
END_METHOD

METHOD Enter
nEnter := nEnter + 1;
END_METHOD

METHOD ABSTRACT Execute : E_State
VAR_IN_OUT
    ctx : ST_Context;
END_VAR
END_METHOD

METHOD Leave
nLeave := nLeave + 1;
END_METHOD

PROPERTY Id : E_State
GET
Id := eId;
END_GET
END_PROPERTY

FUNCTION_BLOCK FB_Idle EXTENDS FB_StateBase
END_FUNCTION_BLOCK

METHOD Execute : E_State
VAR_IN_OUT
    ctx : ST_Context;
END_VAR
nExec := nExec + 1;
Execute := E_State.IDLE;
IF ctx.bStart THEN
    ctx.bStart := FALSE;
    ctx.nProduced := 0;
    Execute := E_State.STARTING;
END_IF
END_METHOD

FUNCTION_BLOCK FB_Starting EXTENDS FB_StateBase
VAR
    tDelay : TON;
END_VAR
END_FUNCTION_BLOCK

METHOD Enter
SUPER^.Enter();
tDelay(IN := FALSE);
END_METHOD

METHOD Execute : E_State
VAR_IN_OUT
    ctx : ST_Context;
END_VAR
nExec := nExec + 1;
tDelay(IN := TRUE, PT := T#30MS);
IF tDelay.Q THEN
    Execute := E_State.RUNNING;
ELSE
    Execute := E_State.STARTING;
END_IF
END_METHOD

FUNCTION_BLOCK FB_Running EXTENDS FB_StateBase
END_FUNCTION_BLOCK

METHOD Execute : E_State
VAR_IN_OUT
    ctx : ST_Context;
END_VAR
nExec := nExec + 1;
ctx.nProduced := ctx.nProduced + 1;
IF ctx.bStop OR ctx.nProduced >= ctx.nTarget THEN
    Execute := E_State.STOPPING;
ELSE
    Execute := E_State.RUNNING;
END_IF
END_METHOD

FUNCTION_BLOCK FB_Stopping EXTENDS FB_StateBase
END_FUNCTION_BLOCK

METHOD Execute : E_State
VAR_IN_OUT
    ctx : ST_Context;
END_VAR
nExec := nExec + 1;
ctx.nCycles := ctx.nCycles + 1;
ctx.bStop := FALSE;
Execute := E_State.IDLE;
END_METHOD

FUNCTION_BLOCK FB_Machine
VAR_IN_OUT
    ctx : ST_Context;
END_VAR
VAR_OUTPUT
    eCurrent : E_State := E_State.IDLE;
    nTransitions : INT;
    nTrace : DINT;
END_VAR
VAR
    fbIdle : FB_Idle(eMyId := E_State.IDLE);
    fbStarting : FB_Starting(eMyId := E_State.STARTING);
    fbRunning : FB_Running(eMyId := E_State.RUNNING);
    fbStopping : FB_Stopping(eMyId := E_State.STOPPING);
    aStates : ARRAY[0..3] OF I_State;
    bInit : BOOL;
    eNext : E_State;
    i : INT;
END_VAR
IF NOT bInit THEN
    aStates[0] := fbIdle;
    aStates[1] := fbStarting;
    aStates[2] := fbRunning;
    aStates[3] := fbStopping;
    bInit := TRUE;
END_IF
eNext := aStates[eCurrent].Execute(ctx);
IF eNext <> eCurrent THEN
    aStates[eCurrent].Leave();
    eCurrent := eNext;
    aStates[eCurrent].Enter();
    nTransitions := nTransitions + 1;
    nTrace := nTrace * 10 + TO_DINT(aStates[eCurrent].Id);
END_IF
END_FUNCTION_BLOCK

PROGRAM main
VAR
    ctx : ST_Context;
    fbM : FB_Machine;
    nScan : INT;
    idSum : INT;
    k : INT;
    ids : ARRAY[0..3] OF INT;
END_VAR
nScan := nScan + 1;
IF nScan = 2 THEN ctx.bStart := TRUE; END_IF
fbM(ctx := ctx);
FOR k := 0 TO 3 DO
    ids[k] := TO_INT(fbM.aStates[k].Id);
END_FOR
END_PROGRAM
"""


COMMAND_QUEUE = """
INTERFACE ICommand
  METHOD Execute : BOOL
    VAR_IN_OUT acc : DINT; END_VAR
  END_METHOD
  PROPERTY Name : STRING
  END_PROPERTY
END_INTERFACE

FUNCTION_BLOCK FB_AddCmd IMPLEMENTS ICommand
  VAR_INPUT nValue : DINT; END_VAR
  VAR nRuns : INT; END_VAR
  METHOD Execute : BOOL
    VAR_IN_OUT acc : DINT; END_VAR
    acc := acc + nValue;
    nRuns := nRuns + 1;
    Execute := TRUE;
  END_METHOD
  PROPERTY Name : STRING
    GET
      Name := CONCAT('ADD', DINT_TO_STRING(nValue));
    END_GET
  END_PROPERTY
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_MulCmd IMPLEMENTS ICommand
  VAR_INPUT nFactor : DINT := 2; END_VAR
  METHOD Execute : BOOL
    VAR_IN_OUT acc : DINT; END_VAR
    acc := acc * nFactor;
    Execute := TRUE;
  END_METHOD
  PROPERTY Name : STRING
    GET
      Name := CONCAT('MUL', DINT_TO_STRING(nFactor));
    END_GET
  END_PROPERTY
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_WaitCmd IMPLEMENTS ICommand
  VAR_INPUT nCycles : INT := 1; END_VAR
  VAR nLeft : INT; bArmed : BOOL; END_VAR
  METHOD Execute : BOOL
    VAR_IN_OUT acc : DINT; END_VAR
    IF NOT bArmed THEN
      nLeft := nCycles;
      bArmed := TRUE;
    END_IF
    nLeft := nLeft - 1;
    IF nLeft <= 0 THEN
      bArmed := FALSE;
      Execute := TRUE;
    END_IF
  END_METHOD
  PROPERTY Name : STRING
    GET
      Name := 'WAIT';
    END_GET
  END_PROPERTY
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_CmdQueue
  VAR CONSTANT SIZE : INT := 4; END_VAR
  VAR_OUTPUT nOverflows : INT; nDone : INT; nIdle : INT; sLog : STRING(200); END_VAR
  VAR aBuf : ARRAY[0..3] OF ICommand; nHead, nTail, nCount : INT; END_VAR
  METHOD Push : BOOL
    VAR_INPUT cmd : ICommand; END_VAR
    IF nCount >= SIZE THEN
      nOverflows := nOverflows + 1;
      RETURN;
    END_IF
    aBuf[nTail] := cmd;
    nTail := (nTail + 1) MOD SIZE;
    nCount := nCount + 1;
    Push := TRUE;
  END_METHOD
  METHOD Peek : ICommand
    IF nCount > 0 THEN
      Peek := aBuf[nHead];
    END_IF
  END_METHOD
  METHOD Step
    VAR_IN_OUT acc : DINT; END_VAR
    VAR cmd : ICommand; END_VAR
    cmd := Peek();
    IF cmd = NULL THEN
      nIdle := nIdle + 1;
    ELSIF cmd.Execute(acc) THEN
      sLog := CONCAT(CONCAT(sLog, cmd.Name), ';');
      aBuf[nHead] := NULL;
      nHead := (nHead + 1) MOD SIZE;
      nCount := nCount - 1;
      nDone := nDone + 1;
    END_IF
  END_METHOD
END_FUNCTION_BLOCK

PROGRAM main
  VAR
    q : FB_CmdQueue;
    add5 : FB_AddCmd := (nValue := 5);
    addm4 : FB_AddCmd := (nValue := -4);
    add7 : FB_AddCmd := (nValue := 7);
    mul3 : FB_MulCmd := (nFactor := 3);
    wait2 : FB_WaitCmd := (nCycles := 2);
    acc : DINT := 1;
    nScan : INT;
    bPushed7 : BOOL;
    nAccepted : INT;
    ipProbe : ICommand;
    pAdd : POINTER TO FB_AddCmd;
    pMul : POINTER TO FB_MulCmd;
    nProbe : DINT;
  END_VAR
  nScan := nScan + 1;
  IF nScan = 1 THEN
    IF q.Push(add5) THEN nAccepted := nAccepted + 1; END_IF
    IF q.Push(mul3) THEN nAccepted := nAccepted + 1; END_IF
    IF q.Push(wait2) THEN nAccepted := nAccepted + 1; END_IF
    IF q.Push(addm4) THEN nAccepted := nAccepted + 1; END_IF
    bPushed7 := q.Push(add7);
  ELSIF nScan = 5 THEN
    bPushed7 := q.Push(add7);
  END_IF
  q.Step(acc);
  ipProbe := mul3;
  pAdd ?= ipProbe;
  pMul ?= ipProbe;
  IF pAdd = 0 AND pMul <> 0 THEN
    nProbe := pMul^.nFactor * 100;
  END_IF
END_PROGRAM
"""


EVENT_BUS = """
INTERFACE IListener
  METHOD OnEvent : BOOL
    VAR_INPUT nCode : INT; nData : DINT; END_VAR
  END_METHOD
END_INTERFACE

FUNCTION_BLOCK FB_Logger
  VAR_STAT nTotal : DINT; END_VAR
  VAR nOwn : DINT; aLast : ARRAY[0..2] OF INT; idx : INT; END_VAR
  METHOD Log
    VAR_INPUT nCode : INT; END_VAR
    nTotal := nTotal + 1;
    nOwn := nOwn + 1;
    aLast[idx] := nCode;
    idx := (idx + 1) MOD 3;
  END_METHOD
  PROPERTY Total : DINT
    GET
      Total := nTotal;
    END_GET
  END_PROPERTY
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_EventBus
  VAR_OUTPUT nDelivered : INT; nConsumed : INT; nSubs : INT; END_VAR
  VAR aSubs : ARRAY[1..4] OF IListener; aMask : ARRAY[1..4] OF WORD; END_VAR
  METHOD Subscribe : BOOL
    VAR_INPUT itf : IListener; wMask : WORD; END_VAR
    VAR i : INT; END_VAR
    FOR i := 1 TO nSubs DO
      IF aSubs[i] = itf THEN
        Subscribe := FALSE;
        RETURN;
      END_IF
    END_FOR
    IF nSubs < 4 THEN
      nSubs := nSubs + 1;
      aSubs[nSubs] := itf;
      aMask[nSubs] := wMask;
      Subscribe := TRUE;
    END_IF
  END_METHOD
  METHOD Publish : INT
    VAR_INPUT nCode : INT; nData : DINT; END_VAR
    VAR i : INT; END_VAR
    FOR i := 1 TO nSubs DO
      IF (aMask[i] AND SHL(WORD#1, nCode)) <> 0 THEN
        Publish := Publish + 1;
        nDelivered := nDelivered + 1;
        IF aSubs[i].OnEvent(nCode, nData) THEN
          nConsumed := nConsumed + 1;
          EXIT;
        END_IF
      END_IF
    END_FOR
  END_METHOD
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_Sensor IMPLEMENTS IListener
  VAR_INPUT nId : INT; END_VAR
  VAR_OUTPUT nSum : DINT; nHits : INT; bRegistered : BOOL; END_VAR
  VAR log : FB_Logger; END_VAR
  METHOD Register
    VAR_IN_OUT bus : FB_EventBus; END_VAR
    VAR_INPUT wMask : WORD; END_VAR
    bRegistered := bus.Subscribe(THIS^, wMask);
  END_METHOD
  METHOD OnEvent : BOOL
    VAR_INPUT nCode : INT; nData : DINT; END_VAR
    nHits := nHits + 1;
    nSum := nSum + nData * nId;
    log.Log(nCode);
    OnEvent := nCode = 7;
  END_METHOD
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_Tally IMPLEMENTS IListener
  VAR refTarget : REFERENCE TO DINT; END_VAR
  METHOD Bind
    VAR_INPUT target : REFERENCE TO DINT; END_VAR
    refTarget REF= target;
  END_METHOD
  METHOD OnEvent : BOOL
    VAR_INPUT nCode : INT; nData : DINT; END_VAR
    IF __ISVALIDREF(refTarget) THEN
      refTarget := refTarget + nData;
    END_IF
    OnEvent := FALSE;
  END_METHOD
END_FUNCTION_BLOCK

PROGRAM main
  VAR
    bus : FB_EventBus;
    s1 : FB_Sensor := (nId := 1);
    s2 : FB_Sensor := (nId := 2);
    s3 : FB_Sensor := (nId := 3);
    s4 : FB_Sensor := (nId := 4);
    tally : FB_Tally;
    total : DINT;
    bDup, bTally : BOOL;
    r1, r2, r7, r5 : INT;
    nLogTotal : DINT;
    nScan : INT;
  END_VAR
  nScan := nScan + 1;
  IF nScan = 1 THEN
    s1.Register(bus, 16#0006);
    s2.Register(bus := bus, wMask := 16#0084);
    s3.Register(bus, 16#0080);
    bDup := bus.Subscribe(s1, 16#FFFF);
    tally.Bind(total);
    bTally := bus.Subscribe(tally, 16#FFFF);
    s4.Register(bus, 16#FFFF);
  END_IF
  r1 := bus.Publish(1, 10);
  r2 := bus.Publish(2, 100);
  r7 := bus.Publish(nCode := 7, nData := 1000);
  r5 := bus.Publish(5, 3);
  nLogTotal := s3.log.Total;
END_PROGRAM
"""


AXIS = """
TYPE E_AxisState : (Disabled, Standstill, Moving, Homing, ErrorStop); END_TYPE

FUNCTION_BLOCK FB_Axis
  VAR_INPUT bEnable : BOOL; END_VAR
  VAR_OUTPUT eState : E_AxisState; nErrorId : UDINT; END_VAR
  VAR
    fPos : LREAL;
    fTarget : LREAL;
    fVel : LREAL := 10.0;
    fMaxPos : LREAL := 1000.0;
    tHoming : TON;
    nMoves : INT;
  END_VAR
  PROPERTY Position : LREAL
    GET
      Position := fPos;
    END_GET
  END_PROPERTY
  PROPERTY Velocity : LREAL
    GET
      Velocity := fVel;
    END_GET
    SET
      IF Velocity > 0 AND Velocity <= 50 THEN
        fVel := Velocity;
      ELSE
        nErrorId := 16#4001;
      END_IF
    END_SET
  END_PROPERTY
  PROPERTY InPosition : BOOL
    GET
      InPosition := eState = Standstill AND ABS(fPos - fTarget) < 0.001;
    END_GET
  END_PROPERTY
  METHOD MoveAbsolute : BOOL
    VAR_INPUT fPosition : LREAL; END_VAR
    IF eState <> Standstill THEN
      MoveAbsolute := FALSE;
    ELSIF fPosition < 0 OR fPosition > fMaxPos THEN
      nErrorId := 16#4002;
      eState := ErrorStop;
    ELSE
      fTarget := fPosition;
      eState := Moving;
      nMoves := nMoves + 1;
      MoveAbsolute := TRUE;
    END_IF
  END_METHOD
  METHOD Home : BOOL
    IF eState = Standstill THEN
      eState := Homing;
      tHoming(IN := FALSE);
      Home := TRUE;
    END_IF
  END_METHOD
  METHOD Reset
    IF eState = ErrorStop THEN
      eState := Standstill;
      nErrorId := 0;
    END_IF
  END_METHOD
  METHOD PRIVATE Cyclic
    VAR fStep : LREAL; END_VAR
    CASE eState OF
      Disabled:
        IF bEnable THEN eState := Standstill; END_IF
      Standstill, Moving, Homing, ErrorStop:
        IF NOT bEnable THEN eState := Disabled; END_IF
    END_CASE
    CASE eState OF
      Moving:
        fStep := fTarget - fPos;
        IF ABS(fStep) <= fVel THEN
          fPos := fTarget;
          eState := Standstill;
        ELSIF fStep > 0 THEN
          fPos := fPos + fVel;
        ELSE
          fPos := fPos - fVel;
        END_IF
      Homing:
        tHoming(IN := TRUE, PT := T#20MS);
        IF tHoming.Q THEN
          fPos := 0;
          fTarget := 0;
          eState := Standstill;
        END_IF
    END_CASE
  END_METHOD
  Cyclic();
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_AxisSoftLimit EXTENDS FB_Axis
  VAR_INPUT fSoftMax : LREAL := 500.0; END_VAR
  METHOD MoveAbsolute : BOOL
    VAR_INPUT fPosition : LREAL; END_VAR
    MoveAbsolute := SUPER^.MoveAbsolute(MIN(fPosition, fSoftMax));
  END_METHOD
  SUPER^();
END_FUNCTION_BLOCK

PROGRAM main
  VAR
    ax : FB_Axis;
    ax2 : FB_AxisSoftLimit;
    refAx : REFERENCE TO FB_Axis;
    bEn : BOOL := TRUE;
    nStep, nScan, nDoneScan, nFinalScan : INT;
    ok1, ok2, ok3, ok4, ok5 : BOOL;
    fPos1, fPos2, fPos3, fPosRead, fVelRead : LREAL;
    nErr1, nErr2 : UDINT;
  END_VAR
  nScan := nScan + 1;
  ax(bEnable := bEn);
  ax2(bEnable := TRUE);
  IF nScan = 1 THEN
    refAx REF= ax2;
    refAx.Velocity := 50.0;
    ok5 := refAx.MoveAbsolute(2000.0);
  END_IF
  CASE nStep OF
    0:
      IF ax.eState = Standstill THEN
        ax.Velocity := 25.0;
        ok1 := ax.MoveAbsolute(100.0);
        nStep := 10;
      END_IF
    10:
      IF ax.InPosition THEN
        fPos1 := ax.Position;
        ax.Velocity := 80.0;
        nErr1 := ax.nErrorId;
        ok2 := ax.MoveAbsolute(2000.0);
        nStep := 20;
      END_IF
    20:
      IF ax.eState = ErrorStop THEN
        nErr2 := ax.nErrorId;
        ax.Reset();
        ok3 := ax.Home();
        nStep := 30;
      END_IF
    30:
      IF ax.eState = Standstill THEN
        fPos2 := ax.Position;
        nDoneScan := nScan;
        ok4 := ax.MoveAbsolute(30);
        nStep := 40;
      END_IF
    40:
      IF ax.InPosition THEN
        fPos3 := ax.Position;
        nStep := 50;
        bEn := FALSE;
      END_IF
    50:
      IF ax.eState = Disabled THEN
        nStep := 60;
        nFinalScan := nScan;
      END_IF
  END_CASE
  fPosRead := ax.Position;
  fVelRead := ax.Velocity;
END_PROGRAM
"""


RECIPES = """
TYPE ST_Ingredient :
STRUCT
    sName : STRING(20);
    fAmount : REAL;
    nSilo : INT;
END_STRUCT
END_TYPE

TYPE ST_Recipe :
STRUCT
    sName : STRING(20);
    nCount : INT;
    aItems : ARRAY[1..5] OF ST_Ingredient;
END_STRUCT
END_TYPE

TYPE ST_RecipeEx EXTENDS ST_Recipe :
STRUCT
    fMixTime : REAL;
END_STRUCT
END_TYPE

FUNCTION SumAmounts : REAL
VAR_IN_OUT
    aItems : ARRAY[*] OF ST_Ingredient;
END_VAR
VAR_INPUT
    nCount : INT;
END_VAR
VAR
    i, nLast : DINT;
END_VAR
nLast := MIN(UPPER_BOUND(aItems, 1), LOWER_BOUND(aItems, 1) + nCount - 1);
FOR i := LOWER_BOUND(aItems, 1) TO nLast DO
    SumAmounts := SumAmounts + aItems[i].fAmount;
END_FOR
END_FUNCTION

FUNCTION_BLOCK FB_RecipeManager
VAR_OUTPUT
    nErrors : INT;
END_VAR
VAR
    aRecipes : ARRAY[0..3] OF ST_Recipe;
    nRecipes : INT;
END_VAR
END_FUNCTION_BLOCK

METHOD Find : INT
VAR_INPUT
    sName : STRING(20);
END_VAR
VAR
    i : INT;
END_VAR
Find := -1;
FOR i := 0 TO nRecipes - 1 DO
    IF aRecipes[i].sName = sName THEN
        Find := i;
        EXIT;
    END_IF
END_FOR
END_METHOD

METHOD Add : BOOL
VAR_INPUT
    sName : STRING(20);
END_VAR
IF nRecipes <= 3 AND Find(sName) < 0 THEN
    aRecipes[nRecipes].sName := sName;
    nRecipes := nRecipes + 1;
    Add := TRUE;
ELSE
    nErrors := nErrors + 1;
END_IF
END_METHOD

METHOD AddItem : BOOL
VAR_INPUT
    sRecipe : STRING(20);
    sItem : STRING(20);
    fAmount : REAL;
    nSilo : INT;
END_VAR
VAR
    idx : INT;
    n : INT;
END_VAR
idx := Find(sRecipe);
IF idx < 0 THEN
    nErrors := nErrors + 1;
ELSIF aRecipes[idx].nCount >= 5 THEN
    nErrors := nErrors + 1;
ELSE
    n := aRecipes[idx].nCount + 1;
    aRecipes[idx].nCount := n;
    aRecipes[idx].aItems[n].sName := sItem;
    aRecipes[idx].aItems[n].fAmount := fAmount;
    aRecipes[idx].aItems[n].nSilo := nSilo;
    AddItem := TRUE;
END_IF
END_METHOD

METHOD Get : ST_Recipe
VAR_INPUT
    sName : STRING(20);
END_VAR
VAR
    idx : INT;
END_VAR
idx := Find(sName);
IF idx >= 0 THEN
    Get := aRecipes[idx];
END_IF
END_METHOD

METHOD Scaled : ST_Recipe
VAR_INPUT
    sName : STRING(20);
    fFactor : REAL;
END_VAR
VAR
    i : INT;
END_VAR
Scaled := Get(sName);
FOR i := 1 TO Scaled.nCount DO
    Scaled.aItems[i].fAmount := Scaled.aItems[i].fAmount * fFactor;
END_FOR
END_METHOD

METHOD Total : REAL
VAR_INPUT
    sName : STRING(20);
END_VAR
VAR
    r : ST_Recipe;
END_VAR
r := Get(sName);
Total := SumAmounts(r.aItems, r.nCount);
END_METHOD

PROPERTY Count : INT
GET
    Count := nRecipes;
END_GET
END_PROPERTY

PROGRAM main
VAR
    mgr : FB_RecipeManager;
    bInit : BOOL;
    nOk : INT;
    r : ST_Recipe;
    recEx : ST_RecipeEx;
    aLocal : ARRAY[-2..2] OF ST_Ingredient;
    i : INT;
    fBread, fCake, fScaled, fEx, fLocal : REAL;
    sSecond : STRING(20);
    nSilo, nMissing, nCount : INT;
END_VAR
IF NOT bInit THEN
    bInit := TRUE;
    IF mgr.Add('Bread') THEN nOk := nOk + 1; END_IF
    IF mgr.Add('Cake') THEN nOk := nOk + 1; END_IF
    IF mgr.Add('Bread') THEN nOk := nOk + 1; END_IF
    IF mgr.AddItem('Bread', 'Flour', 500.0, 1) THEN nOk := nOk + 1; END_IF
    IF mgr.AddItem('Bread', 'Water', 300.0, 2) THEN nOk := nOk + 1; END_IF
    IF mgr.AddItem(sRecipe := 'Bread', sItem := 'Salt', fAmount := 10.0, nSilo := 3) THEN nOk := nOk + 1; END_IF
    IF mgr.AddItem('Cake', 'Sugar', 200.0, 4) THEN nOk := nOk + 1; END_IF
    IF mgr.AddItem('Cake', 'Flour', 250.0, 1) THEN nOk := nOk + 1; END_IF
    IF mgr.AddItem('Pizza', 'Cheese', 1.0, 9) THEN nOk := nOk + 1; END_IF
END_IF
r := mgr.Scaled('Bread', 1.5);
fBread := mgr.Total('Bread');
fCake := mgr.Total('Cake');
fScaled := SumAmounts(r.aItems, r.nCount);
sSecond := r.aItems[2].sName;
nSilo := mgr.Get('Cake').aItems[2].nSilo;
nMissing := mgr.Get('Nope').nCount;
nCount := mgr.Count;
recEx.sName := 'Mix';
recEx.fMixTime := 2.5;
recEx.aItems[1].fAmount := 3.0;
recEx.nCount := 1;
fEx := SumAmounts(recEx.aItems, recEx.nCount) * recEx.fMixTime;
FOR i := -2 TO 2 DO
    aLocal[i].fAmount := INT_TO_REAL(i + 10);
END_FOR
fLocal := SumAmounts(aLocal, 3);
END_PROGRAM
"""


CONVEYOR_TESTS = """
INTERFACE IMotor
  METHOD Start
  END_METHOD
  METHOD Stop
  END_METHOD
  PROPERTY Running : BOOL
  END_PROPERTY
END_INTERFACE

FUNCTION_BLOCK FB_Motor IMPLEMENTS IMotor
  VAR_OUTPUT bOut : BOOL; nStarts : INT; END_VAR
  METHOD Start
    IF NOT bOut THEN nStarts := nStarts + 1; END_IF
    bOut := TRUE;
  END_METHOD
  METHOD Stop
    bOut := FALSE;
  END_METHOD
  PROPERTY Running : BOOL
    GET
      Running := bOut;
    END_GET
  END_PROPERTY
END_FUNCTION_BLOCK

FUNCTION ScaleParts : INT
  VAR_INPUT n : INT; END_VAR
  ScaleParts := n;
END_FUNCTION

FUNCTION_BLOCK FB_Conveyor
  VAR_INPUT bPartSensor : BOOL; bEStop : BOOL; END_VAR
  VAR_OUTPUT nParts : INT; nScaled : INT; bJam : BOOL; END_VAR
  VAR motor : FB_Motor; ipMotor : IMotor; tDebounce : TON; tJam : TON; rtPart : R_TRIG; END_VAR
  METHOD FB_init : BOOL
    VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; END_VAR
    ipMotor := motor;
  END_METHOD
  METHOD PartSeen : BOOL
    tDebounce(IN := bPartSensor, PT := T#50ms);
    rtPart(CLK := tDebounce.Q);
    PartSeen := rtPart.Q;
  END_METHOD
  METHOD Supervise
    tJam(IN := bPartSensor AND ipMotor.Running, PT := T#2s);
    IF tJam.Q THEN bJam := TRUE; END_IF
  END_METHOD
  IF bEStop OR bJam THEN
    ipMotor.Stop();
  ELSE
    ipMotor.Start();
  END_IF
  IF PartSeen() THEN
    nParts := nParts + 1;
  END_IF
  nScaled := ScaleParts(nParts);
  Supervise();
END_FUNCTION_BLOCK

TEST 'a part is counted once after the 50 ms debounce'
  VAR c : FB_Conveyor; i : INT; END_VAR
  c();
  ASSERT_TRUE(c.ipMotor.Running);
  ASSERT_EQ(c.motor.nStarts, 1);
  c.bPartSensor := TRUE;
  FOR i := 1 TO 5 DO
    c();
    ADVANCE_TIME(T#10ms);
  END_FOR
  ASSERT_EQ(c.nParts, 0);
  ASSERT_EQ(c.tDebounce.ET, T#40ms);
  c();
  ASSERT_EQ(c.nParts, 1);
  c();
  ASSERT_EQ(c.nParts, 1, 'R_TRIG: one count per part');
  c.bPartSensor := FALSE;
  c();
  c.bPartSensor := TRUE;
  c();
  ADVANCE_TIME(T#30ms);
  c();
  c.bPartSensor := FALSE;
  c();
  ASSERT_EQ(c.nParts, 1, 'a 30 ms pulse is filtered');
END_TEST

TEST 'a part blocking the sensor for 2 s is a jam and stops the motor'
  VAR c : FB_Conveyor; END_VAR
  c(bPartSensor := TRUE);
  ADVANCE_TIME(T#1990ms);
  c();
  ASSERT_FALSE(c.bJam);
  ADVANCE_TIME(T#10ms);
  c();
  ASSERT_TRUE(c.bJam);
  ASSERT_TRUE(c.motor.bOut, 'stopped on the next call');
  c();
  ASSERT_FALSE(c.ipMotor.Running);
  ASSERT_EQ(c.motor.nStarts, 1);
  ASSERT_EQ(c.nParts, 1);
END_TEST

TEST 'estop stops and restart counts a second start'
  VAR c : FB_Conveyor; END_VAR
  c();
  c(bEStop := TRUE);
  ASSERT_FALSE(c.motor.Running);
  c(bEStop := FALSE);
  ASSERT_TRUE(c.motor.Running);
  ASSERT_EQ(c.motor.nStarts, 2);
END_TEST

TEST 'a mocked scaling function'
  VAR c : FB_Conveyor; END_VAR
  MOCK_FUNCTION ScaleParts RETURNS 42;
  c();
  c();
  ASSERT_EQ(c.nScaled, 42);
  MOCK_VERIFY_CALL_COUNT(ScaleParts, 2);
END_TEST
"""


def test_state_machine_framework_twincat_layout_fb_init_and_interface_array():
    plc = run(STATE_MACHINE, 12, "twincat")
    # scan 2 starts; STARTING waits 30 ms (scans 3..6); RUNNING produces 3 (scans 7..9); STOPPING (scan 10)
    assert plc["main.fbM.eCurrent"] == "IDLE"
    assert plc["main.fbM.nTransitions"] == 4
    assert plc["main.fbM.nTrace"] == 1230
    assert plc["main.ids"] == [0, 1, 2, 3]  # FB_init(eMyId := ...) of every state
    assert (plc["main.ctx.nProduced"], plc["main.ctx.nCycles"], plc["main.ctx.bStart"]) == (3, 1, False)
    assert [plc[f"main.fbM.{s}.nExec"] for s in ("fbIdle", "fbStarting", "fbRunning", "fbStopping")] == [4, 4, 3, 1]
    assert [plc[f"main.fbM.{s}.nEnter"] for s in ("fbIdle", "fbStarting", "fbRunning", "fbStopping")] == [1, 1, 1, 1]
    assert [plc[f"main.fbM.{s}.nLeave"] for s in ("fbIdle", "fbStarting", "fbRunning", "fbStopping")] == [1, 1, 1, 1]


def test_state_machine_mid_run_values():
    plc = run(STATE_MACHINE, 5, "twincat")
    assert plc["main.fbM.eCurrent"] == "STARTING"  # still STARTING: the TON has 20 ms of 30
    assert plc["main.fbM.fbStarting.nExec"] == 3
    plc.scan(1)
    assert plc["main.fbM.eCurrent"] == "RUNNING" and plc["main.fbM.nTrace"] == 12
    plc.scan(3)
    assert plc["main.fbM.eCurrent"] == "STOPPING" and plc["main.ctx.nProduced"] == 3


def test_command_queue_ring_buffer_of_interfaces_and_downcasts():
    plc = run(COMMAND_QUEUE, 8)
    assert plc["main.acc"] == 21  # ((1 + 5) * 3) - 4 + 7
    assert plc["main.q.sLog"] == "ADD5;MUL3;WAIT;ADD-4;ADD7;"
    assert (plc["main.q.nDone"], plc["main.q.nOverflows"], plc["main.q.nIdle"]) == (5, 1, 2)
    assert (plc["main.q.nHead"], plc["main.q.nTail"], plc["main.q.nCount"]) == (1, 1, 0)
    assert (plc["main.nAccepted"], plc["main.bPushed7"]) == (4, True)
    assert [plc[f"main.{c}.nRuns"] for c in ("add5", "addm4", "add7")] == [1, 1, 1]
    assert plc["main.nProbe"] == 300 and plc["main.pAdd"] is None


def test_command_queue_wait_command_spans_two_scans():
    plc = run(COMMAND_QUEUE, 3)
    assert plc["main.acc"] == 18
    assert (plc["main.q.sLog"], plc["main.wait2.bArmed"], plc["main.wait2.nLeft"]) == ("ADD5;MUL3;", True, 1)
    plc.scan(1)
    assert plc["main.q.sLog"] == "ADD5;MUL3;WAIT;" and not plc["main.wait2.bArmed"]


def test_event_bus_with_this_registration_masks_consumption_and_var_stat_logger():
    plc = run(EVENT_BUS, 2)
    assert (plc["main.r1"], plc["main.r2"], plc["main.r7"], plc["main.r5"]) == (2, 3, 1, 1)
    assert (plc["main.s1.nHits"], plc["main.s1.nSum"]) == (4, 220)
    assert (plc["main.s2.nHits"], plc["main.s2.nSum"]) == (4, 4400)
    assert (plc["main.s3.nHits"], plc["main.s3.nSum"]) == (0, 0)  # code 7 consumed by s2 first
    assert plc["main.total"] == 226  # tally through REFERENCE TO
    assert (plc["main.bus.nDelivered"], plc["main.bus.nConsumed"], plc["main.bus.nSubs"]) == (14, 2, 4)
    assert (plc["main.bDup"], plc["main.bTally"], plc["main.s4.bRegistered"]) == (False, True, False)
    assert plc["main.s1.bRegistered"] and plc["main.s3.bRegistered"]
    assert plc["main.s1.log.aLast"] == [2, 2, 1] and plc["main.s2.log.aLast"] == [7, 7, 2]
    assert (plc["main.s1.log.nOwn"], plc["main.s3.log.nOwn"], plc["main.nLogTotal"]) == (4, 0, 8)
    assert plc["main.bus.aMask"] == [6, 132, 128, 65535]


def test_axis_simulation_with_properties_timer_in_a_method_and_soft_limit_override():
    plc = run(AXIS, 14)
    assert plc["main.nStep"] == 60
    assert (plc["main.fPos1"], plc["main.fPos2"], plc["main.fPos3"]) == (100.0, 0.0, 30.0)
    assert (plc["main.nErr1"], plc["main.nErr2"]) == (0x4001, 0x4002)
    assert (plc["main.ok1"], plc["main.ok2"], plc["main.ok3"], plc["main.ok4"], plc["main.ok5"]) == (
        True,
        False,
        True,
        True,
        True,
    )
    assert (plc["main.nDoneScan"], plc["main.nFinalScan"]) == (9, 12)
    assert (plc["main.fPosRead"], plc["main.fVelRead"]) == (30.0, 25.0)  # 80 was refused by the setter
    assert (plc["main.ax.nMoves"], plc["main.ax.nErrorId"], plc["main.ax.eState"]) == (2, 0, "Disabled")
    assert (plc["main.ax2.fPos"], plc["main.ax2.fTarget"], plc["main.ax2.eState"]) == (500.0, 500.0, "Standstill")
    assert plc["main.refAx"] == "REF(main.ax2)"


def test_axis_positions_while_moving():
    plc = run(AXIS, 3)
    assert (plc["main.ax.fPos"], plc["main.ax.eState"], plc["main.ax2.fPos"]) == (50.0, "Moving", 100.0)
    plc.scan(5)  # scan 8: homing, 10 ms of 20
    assert (plc["main.ax.eState"], plc["main.nStep"], plc["main.ax.fPos"]) == ("Homing", 30, 100.0)


def test_recipe_manager_structs_methods_returning_structs_and_conformant_arrays():
    plc = run(RECIPES, 3, "twincat")
    assert (plc["main.nOk"], plc["main.mgr.nErrors"], plc["main.nCount"]) == (7, 2, 2)
    assert (plc["main.fBread"], plc["main.fCake"], plc["main.fScaled"]) == (810.0, 450.0, 1215.0)
    assert [it["fAmount"] for it in plc["main.r.aItems"]] == [750.0, 450.0, 15.0, 0.0, 0.0]
    assert (plc["main.sSecond"], plc["main.nSilo"], plc["main.nMissing"]) == ("Water", 1, 0)
    assert (plc["main.fEx"], plc["main.fLocal"]) == (7.5, 27.0)
    assert plc["main.mgr.aRecipes"][1]["aItems"][0]["sName"] == "Sugar"
    assert plc["main.r.sName"] == "Bread" and plc["main.r.nCount"] == 3


def test_st_unit_tests_of_a_conveyor_with_an_interface_timers_and_a_mock():
    results = TestSuite(compile_text(CONVEYOR_TESTS, "conveyor.st", dialect="codesys"), "10s").run_all()
    assert [(r.case.name, r.passed) for r in results] == [
        ("a part is counted once after the 50 ms debounce", True),
        ("a part blocking the sensor for 2 s is a jam and stops the motor", True),
        ("estop stops and restart counts a second start", True),
        ("a mocked scaling function", True),
    ]


def test_st_unit_test_failure_of_the_conveyor_reports_values():
    src = CONVEYOR_TESTS.replace("ASSERT_EQ(c.motor.nStarts, 2);", "ASSERT_EQ(c.motor.nStarts, 3);")
    results = {r.case.name: r for r in TestSuite(compile_text(src, "conveyor.st", dialect="codesys"), "10s").run_all()}
    bad = results["estop stops and restart counts a second start"]
    assert not bad.passed and (bad.report.actual, bad.report.expected) == ("2", "3")
    assert sum(r.passed for r in results.values()) == 3


SHAPES = """
INTERFACE IShape
  METHOD Area : REAL END_METHOD
END_INTERFACE
INTERFACE IScalable
  METHOD Scale VAR_INPUT f : REAL; END_VAR END_METHOD
END_INTERFACE
FUNCTION_BLOCK FB_Rect IMPLEMENTS IShape, IScalable
  VAR_INPUT w, h : REAL; END_VAR
  METHOD Area : REAL Area := w * h; END_METHOD
  METHOD Scale VAR_INPUT f : REAL; END_VAR VAR_INST nScaled : INT; END_VAR
    w := w * f; h := h * f; nScaled := nScaled + 1;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK FB_Circle IMPLEMENTS IShape
  VAR_INPUT r : REAL; END_VAR
  METHOD Area : REAL Area := 3.0 * r * r; END_METHOD
END_FUNCTION_BLOCK
FUNCTION TotalArea : REAL
  VAR_IN_OUT shapes : ARRAY[*] OF IShape; END_VAR
  VAR i : DINT; sc : IScalable; END_VAR
  FOR i := LOWER_BOUND(shapes, 1) TO UPPER_BOUND(shapes, 1) DO
    IF shapes[i] <> NULL THEN
      sc ?= shapes[i];
      IF sc <> NULL THEN sc.Scale(2.0); END_IF
      TotalArea := TotalArea + shapes[i].Area();
    END_IF
  END_FOR
END_FUNCTION
PROGRAM main
  VAR a : FB_Rect := (w := 1.0, h := 2.0); c : FB_Circle := (r := 1.0);
      arr : ARRAY[1..3] OF IShape; t1, t2 : REAL; ok : BOOL; ipS : IScalable; END_VAR
  arr[1] := a; arr[3] := c;
  t1 := TotalArea(arr);
  ok := __QUERYINTERFACE(arr[3], ipS);
END_PROGRAM
"""


def test_conformant_array_of_interfaces_with_assignment_attempt_and_query_interface():
    plc = run(SHAPES, 1)
    assert (plc["main.t1"], plc["main.a.w"], plc["main.a.h"]) == (11.0, 2.0, 4.0)  # rect scaled x2 then 8 + circle 3
    assert (plc["main.ok"], plc["main.ipS"]) == (False, None)
    plc.scan(1)
    assert (plc["main.t1"], plc["main.a.w"], plc["main.a.h"]) == (35.0, 4.0, 8.0)
    assert plc["main.arr"] == ["FB_Rect", None, "FB_Circle"]
