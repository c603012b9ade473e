/PROG  DEFLEX_STREAM
/ATTR
OWNER		= MNEDITOR;
COMMENT		= "deflex J519 stream";
PROG_SIZE	= 0;
CREATE		= DATE 26-11-29  TIME 09:00:00;
MODIFIED	= DATE 26-11-29  TIME 09:00:00;
FILE_NAME	= ;
VERSION		= 0;
LINE_COUNT	= 9;
MEMORY_SIZE	= 0;
PROTECT		= READ_WRITE;
TCD:  STACK_SIZE	= 0,
      TASK_PRIORITY	= 50,
      TIME_SLICE	= 0,
      BUSY_LAMP_OFF	= 0,
      ABORT_REQUEST	= 0,
      PAUSE_REQUEST	= 0;
DEFAULT_GROUP	= 1,*,*,*,*;
CONTROL_CODE	= 00000000 00000000;
/MN
   1:  !deflex streams the joints (J519) ;
   2:  !Set UTOOL/UFRAME as the CELL.toml ;
   3:  UFRAME_NUM=0 ;
   4:  UTOOL_NUM=1 ;
   5:  !Near the path start (20 deg) ;
   6:  J P[1] 10% FINE ;
   7:  IBGN start[1] ;
   8:  IBGN end[1] ;
   9:  !Stream ended: is_last + stop ;
/POS
P[1]{
   GP1:
	UF : 0, UT : 1,	
	J1=     0.000 deg,	J2=     0.000 deg,	J3=     0.000 deg,
	J4=     0.000 deg,	J5=   -90.000 deg,	J6=     0.000 deg
};
/END
